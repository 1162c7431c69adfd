// Checkpoints of tomodem-dem on several ranks (docs/dem.md, "Checkpoints"): written by 2 ranks
// through HDF5's MPI-IO driver, restarted on 1, 2 and 3 ranks and without mpirun. Like
// test_dem_tool.cpp this is not an MPI program: it starts the tool as a user would.
//
// What must be equal, and why:
//  - the 2-rank checkpoint and the one-process checkpoint of the same step, dataset by dataset,
//    bit for bit (the file is independent of the rank count): the decomposed engine follows the
//    serial trajectory bit for bit with one thread per rank (test_dem_tool.cpp), and the writer
//    puts every particle and every neighbour-list row at its place in id order. The time-series
//    rows are sums over the ranks added in rank order: relative 1e-12 (as test_dem_tool.cpp);
//  - a restart, on any rank count, ends bit for bit on the uninterrupted run (particles, contact
//    table, the final checkpoint's engine state), as the serial restart does: the restart rebuilds
//    the sub-domains at the checkpoint's last neighbour-list build, so every later rebuild and
//    wrap falls on the same step;
//  - a checkpoint of another format or tomodem release is refused on 2 ranks: exit 2, one
//    message naming the file, the attribute and its value, and no file written.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;
namespace h5 = tomodem::h5;

namespace {

const std::string kDem = std::string(TOMODEM_BIN_DIR) + "/tomodem-dem";

struct Ran {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs tomodem-dem in `dir`; ranks 0: without mpirun.
Ran run(const fs::path& dir, int ranks, const std::string& args) {
  const std::string launch = ranks > 0 ? std::string(TOMODEM_MPIEXEC) + " --oversubscribe -np " + std::to_string(ranks) + " " : "";
  const std::string cmd = "cd '" + dir.string() + "' && OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 "
                          "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + launch + kDem + " " + args + " >stdout.txt 2>stderr.txt";
  Ran r;
  const int st = std::system(cmd.c_str());
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  r.out = slurp(dir / "stdout.txt");
  r.err = slurp(dir / "stderr.txt");
  fs::remove(dir / "stdout.txt");
  fs::remove(dir / "stderr.txt");
  return r;
}

/// Scene A of docs/dem.md at 12^3 spheres (test_dem_tool.cpp), 200 steps, the list rebuilt
/// every few steps (small skin) so rebuilds fall both sides of the checkpoint at step 100, and a
/// checkpoint every 50 steps (the protocol's writes and the one at the end).
std::string scene(bool sheared) {
  std::string s = R"(materials:
  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}
particles:
  generate: {arrangement: simple_cubic, cells: 12, radius: 0.5e-3, spacing: 0.9837e-3, jitter: 0.015, velocity: 0.1, seed: 3, phase: glass}
physics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}
protocol: {timestep: 1.35e-6, steps: 200, output_interval: 50, checkpoint_interval: 50}
settings: {skin: 2.0e-5, threads: 1}
output: {packing: out.h5, series: series.csv, checkpoint: ck.h5}
)";
  if (sheared) s += "boundary: {strain_rate: {xy: 40.0}}\n";
  return s;
}

/// Every dataset of a file, by path.
void datasets(const h5::File& f, const std::string& group, std::vector<std::string>& out) {
  for (const std::string& name : f.children(group)) {
    const std::string path = (group == "/" ? "" : group) + "/" + name;
    try {
      f.shape(path);
      out.push_back(path);
    } catch (...) {
      datasets(f, path, out);
    }
  }
}

/// A copy of a checkpoint with its root attributes replaced (datasets as doubles: the reader
/// converts), the way another version of tomodem would have stamped it.
void restamp(const fs::path& from, const fs::path& to, double format, const std::string& version) {
  const h5::File in(from.string(), h5::File::Mode::read);
  h5::File out(to.string(), h5::File::Mode::create);
  out.set_attr("/", "tomodem_checkpoint_format", format);
  out.set_attr("/", "version", version);
  out.set_attr("/", "tomodem_version", version);
  out.set_attr("/", "scene", in.attr_string("/", "scene"));
  std::vector<std::string> all;
  datasets(in, "/", all);
  for (const auto& d : all) {
    std::vector<std::size_t> dims;
    const auto v = in.read_double(d, &dims);
    out.write(d, v, dims);
  }
  out.close();
}

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> s;
  for (const auto& e : fs::recursive_directory_iterator(dir)) s.insert(fs::relative(e.path(), dir).string());
  return s;
}

bool same_bits(const tomodem::Vec3& a, const tomodem::Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/// Particles and contact table of two packings, bit for bit: the number of differing entries.
long packing_differences(const tomodem::Packing& a, const tomodem::Packing& b) {
  const auto& P = a.particles;
  const auto& Q = b.particles;
  if (P.position.size() != Q.position.size() || a.contacts.size() != b.contacts.size()) return -1;
  long d = 0;
  for (std::size_t i = 0; i < P.position.size(); ++i)
    d += !same_bits(P.position[i], Q.position[i]) || !same_bits(P.velocity[i], Q.velocity[i]) ||
         !same_bits(P.angular_velocity[i], Q.angular_velocity[i]);
  for (std::size_t c = 0; c < a.contacts.size(); ++c)
    d += a.contacts.i[c] != b.contacts.i[c] || a.contacts.j[c] != b.contacts.j[c] ||
         a.contacts.overlap[c] != b.contacts.overlap[c] ||
         !same_bits(a.contacts.normal_force[c], b.contacts.normal_force[c]) ||
         !same_bits(a.contacts.tangential_force[c], b.contacts.tangential_force[c]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) d += a.cell.h(r, c) != b.cell.h(r, c);
  return d;
}

/// Datasets of two checkpoints under `under` ("" for all), bit for bit; /series/rows to
/// relative `series_rel`. Returns what differs.
std::vector<std::string> checkpoint_differences(const fs::path& a, const fs::path& b, const std::string& under,
                                                double series_rel) {
  const h5::File fa(a.string(), h5::File::Mode::read), fb(b.string(), h5::File::Mode::read);
  std::vector<std::string> da, db, out;
  datasets(fa, "/", da);
  datasets(fb, "/", db);
  if (da != db) out.push_back("dataset lists differ");
  for (const auto& d : da) {
    if (d.rfind(under, 0) != 0 || !fb.exists(d)) continue;
    std::vector<std::size_t> sa, sb;
    const auto va = fa.read_double(d, &sa), vb = fb.read_double(d, &sb);
    if (sa != sb || va.size() != vb.size()) {
      out.push_back(d + " (shape)");
      continue;
    }
    const double rel = d == "/series/rows" ? series_rel : 0.0;
    for (std::size_t k = 0; k < va.size(); ++k)
      if (!(va[k] == vb[k] || std::abs(va[k] - vb[k]) <= rel * std::max(std::abs(va[k]), std::abs(vb[k])) ||
            (std::isnan(va[k]) && std::isnan(vb[k])))) {
        out.push_back(d + "[" + std::to_string(k) + "]: " + std::to_string(va[k]) + " vs " + std::to_string(vb[k]));
        break;
      }
  }
  return out;
}

class CheckpointOnRanks : public ::testing::TestWithParam<bool> {};

TEST_P(CheckpointOnRanks, WrittenOnTwoRanksRestartsAnywhereAsIfNeverStopped) {
  const bool sheared = GetParam();
  const fs::path root = fs::temp_directory_path() / ("tomodem_ck_ranks_" + std::to_string(::getpid()) + (sheared ? "_shear" : "_a"));
  fs::remove_all(root);
  fs::create_directories(root);
  std::ofstream(root / "scene.yaml") << scene(sheared);

  // The uninterrupted run, and the first half on one process and on 2 ranks.
  Ran r = run(root, 0, "scene.yaml --output-dir full -q --json full.json");
  ASSERT_EQ(r.code, 0) << r.err;
  r = run(root, 0, "scene.yaml --output-dir half1 --steps 100 -q");
  ASSERT_EQ(r.code, 0) << r.err;
  r = run(root, 2, "scene.yaml --output-dir half2 --steps 100 -q");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(listing(root / "half2"), (std::set<std::string>{"ck.h5", "out.h5", "out.xdmf", "series.csv"}))
      << "a temporary left behind";
  const tomodem::Packing full = tomodem::read_packing((root / "full/out.h5").string());
  const tomodem::Packing half = tomodem::read_packing((root / "half2/out.h5").string());
  ASSERT_GT(full.contacts.size(), 5000u);
  ASSERT_NE(packing_differences(full, half), 0) << "the half run must not already be the end state";

  // The file does not depend on the rank count.
  const auto ck_diff = checkpoint_differences(root / "half1/ck.h5", root / "half2/ck.h5", "", 1e-12);
  EXPECT_TRUE(ck_diff.empty()) << ck_diff.front();
  {
    const h5::File f((root / "half2/ck.h5").string(), h5::File::Mode::read);
    EXPECT_EQ(f.attr_double("/", "written_by_ranks"), 2.0);
    EXPECT_GT(f.read_double("/engine/history").size(), 1000u) << "no contact history in the checkpoint";
  }

  const json jfull = json::parse(slurp(root / "full.json"));
  for (int ranks : {0, 1, 2, 3}) {
    SCOPED_TRACE("restart on " + (ranks ? std::to_string(ranks) + " ranks" : std::string("one process")) +
                 (sheared ? ", sheared cell" : ""));
    const std::string dir = "r" + std::to_string(ranks);
    r = run(root, ranks, "scene.yaml --restart half2/ck.h5 --output-dir " + dir + " -q --json " + dir + ".json");
    ASSERT_EQ(r.code, 0) << r.err;
    const tomodem::Packing got = tomodem::read_packing((root / dir / "out.h5").string());
    EXPECT_EQ(packing_differences(full, got), 0) << "not bitwise the uninterrupted run";
    // The engine state at the end too: the list, its history, the rebuild clock, the forces.
    const auto eng = checkpoint_differences(root / "full/ck.h5", root / dir / "ck.h5", "/engine", 0.0);
    EXPECT_TRUE(eng.empty()) << eng.front();
    const json j = json::parse(slurp(root / (dir + ".json")));
    for (const char* k : {"step", "contacts", "neighbor_rebuilds"}) EXPECT_EQ(j.at(k), jfull.at(k)) << k;
    // The series continues: the rows before the restart come from the checkpoint.
    const auto& sf = full.results.series.at("dem").at("step");
    const auto& sg = got.results.series.at("dem").at("step");
    EXPECT_EQ(sf, sg);
  }
  fs::remove_all(root);
}

INSTANTIATE_TEST_SUITE_P(SceneA, CheckpointOnRanks, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? std::string("ShearedCell") : std::string("Still"); });

TEST(CheckpointOnRanks, AnotherVersionIsRefusedOnceWithNothingWritten) {
  const fs::path root = fs::temp_directory_path() / ("tomodem_ck_ranks_version_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  std::string s = scene(false);
  s.replace(s.find("steps: 200"), 10, "steps: 20");
  std::ofstream(root / "scene.yaml") << s;
  Ran r = run(root, 2, "scene.yaml --output-dir half -q");
  ASSERT_EQ(r.code, 0) << r.err;
  restamp(root / "half/ck.h5", root / "old.h5", 1.0, "tomodem 0.0.9 (git 0123456789ab)");
  restamp(root / "half/ck.h5", root / "format.h5", 7.0, "tomodem 0.1.0 (git 0123456789ab)");
  // The restamped copy of this version restarts (the copy itself is sound).
  restamp(root / "half/ck.h5", root / "same.h5", 1.0, "tomodem 0.1.0 (git 0123456789ab)");
  r = run(root, 2, "scene.yaml --restart same.h5 --output-dir same -q");
  EXPECT_EQ(r.code, 0) << r.err;
  fs::remove_all(root / "same");

  struct Case {
    std::string file, says;
  };
  for (const Case& c : {Case{"old.h5", "old.h5: field '/tomodem_version': value 'tomodem 0.0.9 (git 0123456789ab)': written by another tomodem version"},
                        Case{"format.h5", "format.h5: field '/tomodem_checkpoint_format': value '7': this tomodem-dem"}}) {
    SCOPED_TRACE(c.file);
    const auto before = listing(root);
    r = run(root, 2, "scene.yaml --restart " + c.file + " --output-dir out --json out.json");
    EXPECT_EQ(r.code, 2) << r.err;
    const std::size_t at = r.err.find(c.says);
    EXPECT_NE(at, std::string::npos) << r.err;
    if (at != std::string::npos) EXPECT_EQ(r.err.find(c.says, at + 1), std::string::npos) << "said by more than one rank:\n" << r.err;
    EXPECT_EQ(listing(root), before) << "something was written";
    // The same without mpirun.
    r = run(root, 0, "scene.yaml --restart " + c.file + " --output-dir out --json out.json");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_EQ(listing(root), before) << "something was written";
  }
  fs::remove_all(root);
}

}  // namespace
