#pragma once
// Table-driven bad-input runs for the packing and network tools (issue 16, "never destroy, never
// lie"). A row is one line: {name, tool, args, expected exit code, strings stderr must contain}.
// Each row runs in a fresh folder holding a copy of the prepared inputs ({D} in args stands for
// it; the tool also runs there, so relative names work) and asserts
//   - the exit code (never a signal; a hang is cut after 120 s and fails the row),
//   - that stderr names the file or option and the value (every `names` entry),
//   - that the folder holds exactly what it held before: no output, no *.tmp*, and every input
//     byte for byte unchanged.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

namespace tomodem::bad_input {

namespace fs = std::filesystem;

struct Case {
  std::string name;                // a C identifier (the ctest name)
  std::string tool;                // tomodem-<tool>
  std::string args;                // {D}: the row's folder
  int code;                        // expected exit code
  std::vector<std::string> names;  // stderr must contain each
};
inline std::ostream& operator<<(std::ostream& o, const Case& c) { return o << c.name; }
inline std::string case_name(const ::testing::TestParamInfo<Case>& info) { return info.param.name; }

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

/// The first `fraction` of a file (a cut transfer or an interrupted write).
inline void cut_copy(const fs::path& from, const fs::path& to, double fraction) {
  const std::string all = slurp(from);
  spit(to, all.substr(0, std::size_t(double(all.size()) * fraction)));
}

/// Bytes that are no known format (fixed seed: the same file every run).
inline void random_bytes(const fs::path& p, std::size_t n, unsigned seed = 16) {
  std::mt19937 g(seed);
  std::string s(n, '\0');
  for (auto& c : s) c = char(g() & 0xff);
  spit(p, s);
}

/// A packing file written through the checked writer, then damaged through the raw dataset API
/// (which writes whatever it is given), as a buggy tool or another program could.
template <class F>
void write_damaged(const fs::path& p, const Packing& pk, F damage) {
  h5::File f(p.string(), h5::File::Mode::create);
  write_packing_groups(f, pk);
  damage(f);
  f.close();
}

/// The standard set of files that are not packings: a cut copy of `good`, random bytes, an
/// empty file, plain text, a folder, HDF5 without the packing datasets, a packing without
/// /particles/radius, with /particles/position of shape (N, 2), with fractional phases.
inline void write_not_packings(const fs::path& d, const fs::path& good, const Packing& pk) {
  cut_copy(good, d / "half.h5", 0.5);
  random_bytes(d / "random.h5", 4096);
  spit(d / "empty.h5", "");
  spit(d / "text.h5", "particles: 64\nradius: 0.5e-3\n");
  fs::create_directories(d / "folder.h5");
  {
    h5::File f((d / "plain.h5").string(), h5::File::Mode::create);
    f.write("/x", std::vector<double>{1, 2, 3});
    f.close();
  }
  write_damaged(d / "noradius.h5", pk, [](h5::File& f) { f.remove("/particles/radius"); });
  write_damaged(d / "shape.h5", pk, [&](h5::File& f) {
    f.write("/particles/position", std::vector<double>(2 * pk.particles.size(), 0.0), {pk.particles.size(), 2});
  });
  write_damaged(d / "type.h5", pk, [&](h5::File& f) {
    f.write("/particles/phase", std::vector<double>(pk.particles.size(), 0.5));
  });
}

/// Every file and folder below `d` (relative path -> content; folders map to "<dir>").
inline std::map<std::string, std::string> snapshot(const fs::path& d) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(d)) {
    const std::string rel = fs::relative(e.path(), d).string();
    out[rel] = e.is_directory() ? "<dir>" : slurp(e.path());
  }
  return out;
}

inline std::string substitute(std::string s, const std::string& key, const std::string& value) {
  for (std::size_t p = s.find(key); p != std::string::npos; p = s.find(key, p + value.size()))
    s.replace(p, key.size(), value);
  return s;
}

/// Runs one row against a copy of `inputs`.
inline void run_case(const Case& c, const fs::path& inputs) {
  const fs::path work = fs::temp_directory_path() / ("tomodem-bad-" + std::to_string(::getpid()) + "-" + c.name);
  const fs::path err = work.string() + ".stderr";
  fs::remove_all(work);
  fs::create_directories(work);
  fs::copy(inputs, work, fs::copy_options::recursive);
  const auto before = snapshot(work);
  const std::string cmd = "cd '" + work.string() + "' && OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE timeout 120 " +
                          std::string(TOMODEM_BIN_DIR) + "/tomodem-" + c.tool + " " +
                          substitute(c.args, "{D}", work.string()) + " > /dev/null 2> '" + err.string() + "'";
  const int st = std::system(cmd.c_str());
  const std::string msg = slurp(err);
  ASSERT_TRUE(WIFEXITED(st)) << cmd << "\nended by a signal\n" << msg;
  EXPECT_NE(WEXITSTATUS(st), 124) << cmd << "\ndid not finish within 120 s\n" << msg;
  EXPECT_LE(WEXITSTATUS(st), 128) << cmd << "\nkilled by signal " << WEXITSTATUS(st) - 128 << "\n" << msg;
  EXPECT_EQ(WEXITSTATUS(st), c.code) << cmd << "\n" << msg;
  for (const auto& n : c.names) EXPECT_NE(msg.find(n), std::string::npos) << "stderr lacks '" << n << "':\n" << msg;
  const auto after = snapshot(work);
  for (const auto& [k, v] : after)
    if (!before.count(k)) ADD_FAILURE() << c.name << ": left behind " << k;
  for (const auto& [k, v] : before) {
    const auto it = after.find(k);
    if (it == after.end()) ADD_FAILURE() << c.name << ": removed " << k;
    else if (it->second != v) ADD_FAILURE() << c.name << ": changed " << k;
  }
  fs::remove_all(work);
  fs::remove(err);
}

/// Runs `tomodem-<tool> args` in `dir` with a file-size limit of `limit_kb` KiB and SIGXFSZ
/// ignored, so that writes past the limit fail with EFBIG as on a full disk. Returns the exit
/// code and stderr.
inline std::pair<int, std::string> run_with_full_disk(const std::string& tool, const std::string& args,
                                                      const fs::path& dir, int limit_kb) {
  const fs::path err = dir.string() + ".stderr";
  const std::string cmd = "cd '" + dir.string() + "' && OMP_NUM_THREADS=1 bash -c \"trap '' XFSZ; ulimit -f " +
                          std::to_string(limit_kb) + "; exec " + std::string(TOMODEM_BIN_DIR) + "/tomodem-" + tool +
                          " " + args + "\" > /dev/null 2> '" + err.string() + "'";
  const int st = std::system(cmd.c_str());
  const std::string msg = slurp(err);
  fs::remove(err);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, msg};
}

/// A folder of prepared inputs, made once per test program by `make` and removed at exit.
class InputCache {
 public:
  template <class F>
  InputCache(const std::string& name, F make)
      : dir_(fs::temp_directory_path() / ("tomodem-bad-inputs-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    make(dir_);
  }
  ~InputCache() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
};

}  // namespace tomodem::bad_input
