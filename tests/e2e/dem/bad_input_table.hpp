#pragma once
// Table-driven bad-input checks shared by the tomodem-dem, tomodem-pack and tomodem-sinter
// end-to-end tests (issue 16, "never destroy, never lie"). Each row: the files to write into a
// fresh folder, the arguments (run in that folder), the expected exit code and the substrings the
// message must hold (the file, the field or option, the value). After each run: the folder holds
// exactly the files written (no output, no temporary *.tmp*) and each is unchanged.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace bad_input {

namespace fs = std::filesystem;

struct Case {
  std::string name;
  std::vector<std::pair<std::string, std::string>> files;  ///< name in the case folder -> contents
  std::string args;
  int code;
  std::vector<std::string> needles;  ///< substrings of stderr
};

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Replaces the first `from` in `text` by `to`; fails the test when `from` is not there (a row
/// whose mutation did not apply would test nothing).
inline std::string with(std::string text, const std::string& from, const std::string& to) {
  const auto k = text.find(from);
  EXPECT_NE(k, std::string::npos) << "mutation does not apply: " << from;
  if (k != std::string::npos) text.replace(k, from.size(), to);
  return text;
}

/// Runs every case; returns how many ran.
inline int run_all(const std::string& tool, const std::vector<Case>& cases) {
  const fs::path root = fs::temp_directory_path() /
                        ("tomodem_bad_" + tool + "_" + std::to_string(::getpid()) + "_" +
                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(root);
  fs::create_directories(root);
  std::set<std::string> names;
  for (const Case& c : cases) {
    EXPECT_TRUE(names.insert(c.name).second) << "duplicate case name " << c.name;
    const fs::path dir = root / c.name;
    fs::create_directories(dir);
    std::map<std::string, std::string> written;
    for (const auto& [name, text] : c.files) {
      fs::create_directories((dir / name).parent_path());
      std::ofstream(dir / name, std::ios::binary) << text;
      written[name] = text;
    }
    const fs::path out = root / (c.name + ".out"), err = root / (c.name + ".err");
    const std::string cmd = "cd '" + dir.string() + "' && " + std::string(TOMODEM_BIN_DIR) + "/" + tool + " " + c.args +
                            " -q > '" + out.string() + "' 2> '" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    const std::string msg = slurp(err);
    EXPECT_EQ(code, c.code) << c.name << ": " << msg;
    for (const auto& n : c.needles) EXPECT_NE(msg.find(n), std::string::npos) << c.name << ": no '" << n << "' in: " << msg;
    // Nothing written: the folder holds exactly the inputs, unchanged.
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      const std::string rel = fs::relative(e.path(), dir).string();
      if (e.is_directory()) {
        bool holds_input = false;
        for (const auto& w : written) holds_input = holds_input || w.first.rfind(rel + "/", 0) == 0;
        EXPECT_TRUE(holds_input) << c.name << ": left a folder behind: " << rel;
        continue;
      }
      EXPECT_TRUE(written.count(rel)) << c.name << ": left output behind: " << rel;
      EXPECT_EQ(rel.find(".tmp"), std::string::npos) << c.name << ": left a temporary behind: " << rel;
    }
    for (const auto& [name, text] : written) EXPECT_EQ(slurp(dir / name), text) << c.name << ": changed the input " << name;
  }
  fs::remove_all(root);
  return int(cases.size());
}

}  // namespace bad_input
