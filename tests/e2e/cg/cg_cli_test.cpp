// tomodem-cg from the command line: the worked example of docs/cg.md run as written, summary keys,
// slices, profiles, time averages and displacements through the files.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../../validation/fields/lattices.hpp"
#include "../common/tool_test.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;
using namespace tomodem;

namespace {
class CgCli : public test::ToolTest {
 protected:
  CgCli() : ToolTest("tomodem-cg-e2e") {}
  std::string cg() const { return std::string(TOMODEM_BIN_DIR) + "/tomodem-cg"; }
};

TEST_F(CgCli, WorkedExampleOfTheDocsRunsAsWritten) {
  std::ifstream in(std::string(TOMODEM_SOURCE_DIR) + "/docs/cg.md");
  std::stringstream s;
  s << in.rdbuf();
  const std::string doc = s.str();
  const std::string yaml = test::block_after(doc, "<!-- worked example -->", "yaml");
  const std::string cmds = test::block_after(doc, "<!-- worked example -->", "sh");
  ASSERT_FALSE(yaml.empty());
  ASSERT_FALSE(cmds.empty());
  std::ofstream(path("pack.yaml")) << yaml;
  std::istringstream lines(cmds);
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    if (line.rfind("build/bin/", 0) != 0) continue;
    const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/" + line.substr(10);
    EXPECT_EQ(sh(cmd), 0) << cmd << "\n" << text("stderr.txt");
    ++n;
  }
  EXPECT_GE(n, 3);
  // The documented numbers: the grid integral of ρ is the mass (the cut-off jump, ~1e-5 at 3w),
  // the grid mean of the CG stress is the Love stress (same quadrature), and the packing left
  // by tomodem-pack is in equilibrium to its unbalanced-force ratio (the divergence is small).
  const auto j = json("cg.json");
  for (const char* k : {"tool", "input", "outputs", "wall_time_s", "n_points", "width_m", "kernel", "mass_error",
                        "divergence_residual"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["n_points"].get<int>(), j["dims"][0].get<int>() * j["dims"][1].get<int>() * j["dims"][2].get<int>());
  EXPECT_NEAR(j["width_m"].get<double>(), 1.5 * j["mean_diameter_m"].get<double>(), 1e-12);
  EXPECT_LT(std::abs(j["mass_error"].get<double>()), 1e-4);
  EXPECT_LT(j["divergence_residual"].get<double>(), 0.01);
  EXPECT_LT(j["mean_stress_difference"].get<double>(), 1e-3);
  EXPECT_TRUE(fs::exists(path("stress.h5")) && fs::exists(path("stress.xdmf")));
  const auto p = json("profile.json");
  EXPECT_EQ(p["kernel"], "lucy");
  EXPECT_LT(std::abs(p["mass_error"].get<double>()), 1e-4);
}

TEST_F(CgCli, BondedNetworkFromTomodemBondIsStressFree) {
  // tomodem-bond sets each rest length to the centre distance at bonding, so the stretch forces,
  // and the bond stress, are zero up to the round-off of |d| (1e-16 relative of E a).
  const Packing p = fields::test::spring_lattice(5, 1e-3, Mat3::identity(), 0);
  write_packing(path("lattice.h5"), p);
  ASSERT_EQ(sh(std::string(TOMODEM_BIN_DIR) + "/tomodem-bond lattice.h5 -o bonded.h5 -q --json b.json"), 0)
      << text("stderr.txt");
  ASSERT_EQ(sh(cg() + " bonded.h5 -o f.h5 --json f.json -q"), 0) << text("stderr.txt");
  const auto j = json("f.json");
  EXPECT_EQ(j["bond_forces"], "stretch");
  EXPECT_EQ(j["n_bonds"].get<int>(), 3 * 125);  // touching neighbours of a periodic 5³ lattice: 3 each
  EXPECT_EQ(j["n_bonds"], json("b.json")["n_bonds"]);  // every bond tomodem-bond made is read
  const auto sb = h5::File(path("f.h5"), h5::File::Mode::read).read_double("/fields/stress_bond");
  for (double v : sb) EXPECT_LT(std::abs(v), 1e-9 * 1e9);  // E = 1 GPa
}

TEST_F(CgCli, TimeAverageOfIdenticalSnapshotsIsTheSnapshot) {
  const Packing p = fields::test::spring_lattice(5, 1e-3, Mat3::diagonal({0.999, 1, 1}), 1e4);
  write_packing(path("a.h5"), p);
  write_packing(path("b.h5"), p);
  ASSERT_EQ(sh(cg() + " a.h5 -o one.h5 --json one.json -q"), 0) << text("stderr.txt");
  ASSERT_EQ(sh(cg() + " a.h5 b.h5 -o two.h5 --json two.json -q"), 0) << text("stderr.txt");
  EXPECT_EQ(json("two.json")["snapshots"], 2);
  const auto s1 = h5::File(path("one.h5"), h5::File::Mode::read).read_double("/fields/stress");
  const auto s2 = h5::File(path("two.h5"), h5::File::Mode::read).read_double("/fields/stress");
  ASSERT_EQ(s1.size(), s2.size());
  for (std::size_t k = 0; k < s1.size(); ++k) EXPECT_NEAR(s1[k], s2[k], 1e-12 * std::abs(s1[0]));
}

TEST_F(CgCli, SlicesProfilesAndDisplacementThroughFiles) {
  const Packing ref = fields::test::spring_lattice(6, 1e-3, Mat3::identity(), 0);
  const Packing def = fields::test::spring_lattice(6, 1e-3, Mat3::diagonal({1.001, 1, 1}), 1e4);
  write_packing(path("ref.h5"), ref);
  write_packing(path("def.h5"), def);
  ASSERT_EQ(sh(cg() + " def.h5 --reference ref.h5 -o s.h5 --json s.json --cutoff 6 --width 1.5 -q"), 0)
      << text("stderr.txt");
  h5::File f(path("s.h5"), h5::File::Mode::read);
  const auto eps = f.read_double("/fields/strain");
  // ∇u against the current positions: 1 - 1/1.001 (the test of the library shows the derivation).
  for (std::size_t n = 0; n < eps.size() / 9; ++n) EXPECT_NEAR(eps[9 * n], 1 - 1 / 1.001, 1e-9);
  ASSERT_EQ(sh(cg() + " def.h5 -o sl.h5 --json sl.json --slice y=0.5 --nodes 9 -q"), 0) << text("stderr.txt");
  const auto sl = json("sl.json");
  EXPECT_EQ(sl["n_points"], 81);
  EXPECT_TRUE(sl["mass_error"].is_null());  // a plane holds no mass
  ASSERT_EQ(sh(cg() + " def.h5 -o pr.h5 --json pr.json --profile x --nodes 30 -q"), 0) << text("stderr.txt");
  EXPECT_EQ(json("pr.json")["n_points"], 30);
  EXPECT_NE(text("pr.xdmf").find("Polyvertex"), std::string::npos);
  EXPECT_NE(text("sl.xdmf").find("2DSMesh"), std::string::npos);
}
}  // namespace
