// tomodem-bond and tomodem-young from the command line: summary keys, exit codes, no partial output.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../../validation/mechanics/networks.hpp"
#include "../common/tool_test.hpp"
#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;
using namespace tomodem;

namespace {
class YoungCli : public tomodem::test::ToolTest {
 protected:
  YoungCli() : ToolTest("tomodem-young-e2e") {}
  /// The exit code of `tool args` and its stderr.
  std::pair<int, std::string> run(const std::string& tool, const std::string& args) const {
    const int code = sh(bin(tool) + " " + args);
    return {code, text("stderr.txt")};
  }
  // SC lattice n³ (default 6³), R = 0.5 mm, touching.
  std::string lattice(double E = 1e9, double nu = 0.25, int n = 6) const {
    Packing p = mechanics::test::lattice("simple_cubic", n, 1e-3, 0.5e-3, mechanics::test::ceramic(E, nu));
    write_packing(path("lattice.h5"), p);
    return path("lattice.h5");
  }
};
}  // namespace

TEST_F(YoungCli, BondThenYoungImplicitGivesKnOver2R) {
  auto [code, err] = run("tomodem-bond", lattice() + " -o " + path("bonded.h5") + " --rule ratio --neck-ratio 0.1 " +
                                             "--gap-tolerance 1e-6 --json " + path("bond.json"));
  ASSERT_EQ(code, 0) << err;
  const auto b = json("bond.json");
  EXPECT_EQ(b["n_bonds"], 3 * 216);
  EXPECT_NEAR(b["bonds_per_particle"].get<double>(), 6.0, 1e-12);
  EXPECT_NEAR(b["relative_density"].get<double>(), M_PI / 6, 1e-9);
  EXPECT_TRUE(fs::exists(path("bonded.xdmf")));
  std::tie(code, err) = run("tomodem-young", path("bonded.h5") + " --method implicit --json " + path("young.json"));
  ASSERT_EQ(code, 0) << err;
  const auto y = json("young.json");
  // k_n = 2E* a g_n, E* = E/(2(1−ν²)), g_n = 1 + 4 (a/R)²; E_net = k_n/(2R). Tolerance 0.5%.
  const double Es = 1e9 / (2 * (1 - 0.0625)), a = 0.05e-3, kn = 2 * Es * a * (1 + 4 * 0.01);
  EXPECT_NEAR(y["E"].get<double>() / (kn / 1e-3), 1.0, 0.005);
  EXPECT_NEAR(y["nu"].get<double>(), 0.0, 0.005);
  EXPECT_EQ(y["method"], "implicit");
  EXPECT_EQ(y["C"].size(), 6u);
  EXPECT_TRUE(y.contains("E_error") && y.contains("wall_time_s"));
}

// One contact set for bond, conduct and carve (docs/architecture.md#contacts): by default a pair is
// in contact up to a gap of 1e-3 R̄ in all three. bond's default was 0, so a network it bonded
// lacked the near-touching pairs that conduct counted. Here every pair of the lattice is 5e-4 R̄
// apart: bonded by default, not at a tolerance of 0.
TEST_F(YoungCli, DefaultGapToleranceIsConductsAndCarves) {
  const Packing p = mechanics::test::lattice("simple_cubic", 6, 1.00025e-3, 0.5e-3, mechanics::test::ceramic(1e9, 0.25));
  write_packing(path("gapped.h5"), p);
  auto [code, err] = run("tomodem-bond", path("gapped.h5") + " -o " + path("bonded.h5") + " --rule ratio --json " + path("bond.json"));
  ASSERT_EQ(code, 0) << err;
  EXPECT_EQ(json("bond.json")["n_bonds"], 3 * 216);
  std::tie(code, err) = run("tomodem-bond", path("gapped.h5") + " -o " + path("bonded.h5") +
                                                " --rule ratio --gap-tolerance 0 --json " + path("bond.json"));
  EXPECT_EQ(code, 2) << err;  // no pair in contact: refused, as BondWithoutPairsExits2AndLeavesNoOutput
}

// Necks wider than the face cap (docs/bond.md#dense-networks): SC lattice, a/R = 0.9, ν = 0.45.
// Isolated: g_n held at a/R = 0.5, k_n = 2E* a (1 + 4·0.25), E* = E/(2(1 − ν²)): 1.128e6 N/m.
// The pair's Laguerre face is the cube face (2R)², so the cap E (2R)²/(2R) = 1e6 N/m is lower and
// every bond takes it: E_net = k/(2R) = E, the rigid-body-spring network's modulus.
TEST_F(YoungCli, FaceCapGivesTheSolidModulusOnFullFaces) {
  auto [code, err] = run("tomodem-bond", lattice(1e9, 0.45) + " -o " + path("bonded.h5") +
                                             " --rule ratio --neck-ratio 0.9 --gap-tolerance 1e-6 -q");
  ASSERT_EQ(code, 0) << err;
  std::tie(code, err) = run("tomodem-young", path("bonded.h5") + " --method implicit --json " + path("y.json"));
  ASSERT_EQ(code, 0) << err;
  const auto y = json("y.json");
  EXPECT_NEAR(y["E"].get<double>() / 1e9, 1.0, 1e-6);
  EXPECT_EQ(y["neck_law"]["law"], "face_capped");
  EXPECT_EQ(y["neck_law"]["face_capped_bonds"], 3 * 216);
  EXPECT_EQ(y["neck_law"]["bonds_without_face"], 0);
  std::tie(code, err) =
      run("tomodem-young", path("bonded.h5") + " --method implicit --isolated-necks --json " + path("y.json"));
  ASSERT_EQ(code, 0) << err;
  const auto yi = json("y.json");
  const double Es = 1e9 / (2 * (1 - 0.45 * 0.45)), kn = 2 * Es * 0.45e-3 * (1 + 4 * 0.25);
  EXPECT_NEAR(yi["E"].get<double>() / (kn / 1e-3), 1.0, 1e-6);
  EXPECT_EQ(yi["neck_law"]["law"], "isolated_necks");
  EXPECT_EQ(yi["neck_law"]["face_capped_bonds"], 0);
}

TEST_F(YoungCli, PackingWithoutBondsExits2WithoutOutput) {
  auto [code, err] = run("tomodem-young", lattice() + " --json " + path("y.json"));
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("/bonds"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(path("y.json")));
}

TEST_F(YoungCli, NonSpanningNetworkExits2) {
  // Only the bonds of one x–y plane: nothing spans z.
  mechanics::Network net;
  net.packing = mechanics::test::lattice("simple_cubic", 4, 1e-3, 0.5e-3);
  mechanics::test::bond_ratio(net, 0.1);
  for (std::size_t b = 0; b < net.packing.bonds.size(); ++b)
    if (std::abs(mechanics::bond_vector(net.packing, net.image[b], b).z) > 1e-4) net.packing.bonds.state[b] = 1;
  mechanics::write_network(path("slab.h5"), net);
  auto [code, err] = run("tomodem-young", path("slab.h5") + " --json " + path("y.json"));
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("spans"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(path("y.json")));
}

TEST_F(YoungCli, InconsistentMaterialsExit2) {
  ASSERT_EQ(run("tomodem-bond", lattice(1e9, 0.7) + " -o " + path("b.h5") + " --rule ratio --gap-tolerance 1e-6").first, 0);
  auto [code, err] = run("tomodem-young", path("b.h5") + " --json " + path("y.json"));
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("poisson_ratio"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(path("y.json")));
  // Explicit needs a density.
  ASSERT_EQ(run("tomodem-bond", lattice() + " -o " + path("c.h5") + " --rule ratio --gap-tolerance 1e-6").first, 0);
  std::tie(code, err) = run("tomodem-young", path("c.h5") + " --method explicit --density -1 --json " + path("y.json"));
  EXPECT_EQ(code, 2);
}

TEST_F(YoungCli, BondWithoutPairsExits2AndLeavesNoOutput) {
  Packing p = mechanics::test::lattice("simple_cubic", 4, 1.5e-3, 0.5e-3);
  write_packing(path("loose.h5"), p);
  auto [code, err] = run("tomodem-bond", path("loose.h5") + " -o " + path("out.h5"));
  EXPECT_EQ(code, 2) << err;
  EXPECT_FALSE(fs::exists(path("out.h5")));
  std::tie(code, err) = run("tomodem-bond", path("loose.h5") + " -o " + path("out.h5") + " --rule bogus");
  EXPECT_EQ(code, 2);
  std::tie(code, err) = run("tomodem-bond", "--version");
  EXPECT_EQ(code, 0);
}

TEST_F(YoungCli, BothMethodsReportAgreement) {
  // SC 4³: the explicit test's cost grows as N^(4/3), and the physics is that of the 10³ lattice
  // of the validation tests.
  ASSERT_EQ(run("tomodem-bond", lattice(1e9, 0.25, 4) + " -o " + path("b.h5") + " --rule ratio --gap-tolerance 1e-6").first,
            0);
  auto [code, err] = run("tomodem-young", path("b.h5") + " --method both --transits 20 --points 3 --threads 1 --json " +
                                              path("y.json") + " --curve " + path("curve.csv"));
  ASSERT_EQ(code, 0) << err;
  const auto y = json("y.json");
  // Explicit vs implicit on the lattice: 1% (20 transits: the dynamic error is ~1e-4 at 50 transits
  // and falls as 1/time², so below 1e-3 here), and the reported estimate (rate check) bounds it.
  EXPECT_NEAR(y["explicit_vs_implicit"].get<double>(), 0.0, 0.01);
  EXPECT_GE(y["explicit"]["E_error"].get<double>(), std::abs(y["explicit_vs_implicit"].get<double>()));
  EXPECT_GT(y["explicit"]["E_error_rate"].get<double>(), 0.0);
  EXPECT_TRUE(y["explicit"].contains("inertial_number"));
  EXPECT_TRUE(y["explicit"].contains("unbalanced_force_ratio"));
  EXPECT_TRUE(fs::exists(path("curve.csv")));
  // nu's errors name their unit, so that the report adds them right (implicit: the relative residual).
  EXPECT_EQ(y["units"]["nu_error"], "relative");
  EXPECT_EQ(y["units"]["nu_iso_error"], "relative");
  ASSERT_EQ(run("tomodem-young", path("b.h5") + " --method explicit --transits 20 --points 3 --threads 1 -q --json " +
                                     path("e.json")).first, 0);
  EXPECT_EQ(json("e.json")["units"]["nu_error"], "absolute");
  EXPECT_EQ(json("e.json")["nu_error"], json("e.json")["explicit"]["nu_error"]);
  EXPECT_FALSE(y["nu_outside_bounds"].get<bool>());
  // An option of the method not run is refused, not ignored (implicit is the default).
  std::tie(code, err) = run("tomodem-young", path("b.h5") + " --transits 7 --json " + path("t.json"));
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("applies to explicit only"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(path("t.json")));
}

// An explicit test stopped by --max-steps ended with exit 1 and no output ("--max-steps reached").
// Like a solve at its iteration cap it now gives E from the points measured and says so:
// explicit.max_steps_reached and target_reached, a warning, exit 4. A cap too small for any E
// (fewer than three rate segments) is refused before the run: exit 2 naming --max-steps.
TEST_F(YoungCli, ExplicitTestStoppedByMaxStepsIsReportedShort) {
  ASSERT_EQ(run("tomodem-bond", lattice(1e9, 0.25, 4) + " -o " + path("b.h5") + " --rule ratio --gap-tolerance 1e-6").first,
            0);
  const std::string args = path("b.h5") + " --method explicit --transits 20 --points 6 --no-rate-check --threads 1";
  auto [code, err] = run("tomodem-young", args + " --json " + path("full.json"));
  ASSERT_EQ(code, 0) << err;
  const auto full = json("full.json");
  EXPECT_FALSE(full["explicit"].value("max_steps_reached", true));
  EXPECT_TRUE(full["target_reached"].get<bool>());
  const long segment = full["explicit"]["steps"].get<long>() / 7;  // segment 0 and 6 points
  ASSERT_GT(segment, 0);
  std::tie(code, err) = run("tomodem-young", args + " --max-steps " + std::to_string(4 * segment) + " --json " +
                                                 path("short.json") + " --curve " + path("short.csv"));
  ASSERT_EQ(code, 4) << err;  // the README's code for a run that ends short of what was asked
  const auto y = json("short.json");
  EXPECT_TRUE(y["explicit"]["max_steps_reached"].get<bool>());
  EXPECT_FALSE(y["target_reached"].get<bool>());
  EXPECT_EQ(y["explicit"]["curve"]["strain"].size(), 4u);
  EXPECT_LE(y["explicit"]["steps"].get<long>(), 4 * segment);
  EXPECT_NEAR(y["E"].get<double>() / full["E"].get<double>(), 1.0, 0.05);
  EXPECT_NE(err.find("--max-steps " + std::to_string(4 * segment) + " reached"), std::string::npos) << err;
  EXPECT_TRUE(fs::exists(path("short.csv")));
  // Two segments measure no slope: refused before the run, nothing written.
  std::tie(code, err) = run("tomodem-young", args + " --max-steps " + std::to_string(2 * segment) + " --json " +
                                                 path("none.json"));
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("--max-steps"), std::string::npos) << err;
  EXPECT_NE(err.find("before it can measure E"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(path("none.json")));
}

// A solve stopped by its iteration cap gives numbers, but says so: the summary's converged and
// target_reached are false, E_error carries the residual (far above the tolerance), a warning
// names the cause, and the exit code is 4.
// A disordered network needs tens of CG iterations, so a cap of 2 cannot meet 1e-8.
TEST_F(YoungCli, SolveStoppedByItsIterationCapIsReportedUnconverged) {
  Packing p = mechanics::test::lattice("simple_cubic", 6, 1e-3, 0.5e-3, mechanics::test::ceramic(1e9, 0.25));
  for (std::size_t i = 0; i < p.particles.size(); ++i)  // jitter, so CG does not converge at once
    p.particles.position[i] += Vec3{0.02e-3 * std::sin(1.7 * i), 0.02e-3 * std::cos(2.3 * i), 0.02e-3 * std::sin(0.9 * i + 1)};
  write_packing(path("jittered.h5"), p);
  auto [code, err] = run("tomodem-bond", path("jittered.h5") + " -o " + path("bonded.h5") +
                                             " --rule ratio --neck-ratio 0.1 --gap-tolerance 0.1e-3");
  ASSERT_EQ(code, 0) << err;
  std::tie(code, err) = run("tomodem-young", path("bonded.h5") + " --method implicit --solver amg --tolerance 1e-8 "
                                             "--max-iterations 2 --json " + path("capped.json"));
  ASSERT_EQ(code, 4) << err;  // the README's code for a run that ends short of what was asked
  const auto y = json("capped.json");
  EXPECT_FALSE(y["implicit"]["converged"].get<bool>());
  EXPECT_FALSE(y["target_reached"].get<bool>());
  EXPECT_GT(y["E_error"].get<double>(), 1e-6);
  EXPECT_NE(err.find("stopped before its tolerance"), std::string::npos) << err;
  std::tie(code, err) = run("tomodem-young", path("bonded.h5") + " --method implicit --solver amg --tolerance 1e-8 --json " +
                                                 path("free.json"));
  ASSERT_EQ(code, 0) << err;
  EXPECT_TRUE(json("free.json")["implicit"]["converged"].get<bool>());
  EXPECT_LE(json("free.json")["E_error"].get<double>(), 1e-7);  // true residual, a little above the recurrence
}
