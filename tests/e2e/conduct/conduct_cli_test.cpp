// tomodem-conduct from the command line: outputs, summary keys, exit codes, no partial output.
#include <gtest/gtest.h>

#include <functional>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../../validation/network/lattice.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;
using namespace tomodem;

namespace {
const std::string kTool = std::string(TOMODEM_BIN_DIR) + "/tomodem-conduct";

struct CliResult {
  int code;
  std::string err;
};

class ConductCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("tomodem-conduct-e2e-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  CliResult run(const std::string& args) const {
    const std::string err = path("stderr.txt");
    const int st = std::system((kTool + " " + args + " > " + path("stdout.txt") + " 2> " + err).c_str());
    std::ifstream in(err);
    std::stringstream s;
    s << in.rdbuf();
    return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, s.str()};
  }
  nlohmann::json summary(const std::string& file) const {
    std::ifstream in(file);
    return nlohmann::json::parse(in);
  }
  // Lattice 5×4×4 of spheres R = 5 µm, bonds a = 1 µm, σ = 1e4 S/m: σ_eff = 2σa/(2R) = 2000 S/m.
  std::string lattice(bool periodic = false, double neck_radius = 1e-6) const {
    Packing p = network::test::sc_lattice(5, 4, 4, 5e-6, neck_radius, periodic);
    p.materials[0].name = "LSM";
    p.materials[0].conductivity = 1e4;
    p.materials[1].name = "YSZ";
    p.materials[1].conductivity = 1.0;
    const std::string f = path(periodic ? "periodic.h5" : "lattice.h5");
    write_packing(f, p);
    return f;
  }
  fs::path dir_;
};
}  // namespace

TEST_F(ConductCli, HelpAndVersion) {
  EXPECT_EQ(run("--help").code, 0);
  EXPECT_EQ(run("--version").code, 0);
  std::ifstream in(path("stdout.txt"));
  std::string line;
  std::getline(in, line);
  EXPECT_NE(line.find("tomodem"), std::string::npos);
  EXPECT_EQ(run("--no-such-flag").code, 2);
}

// The closed forms of the lattice tests (σ = 2σ_s a per edge, 2000 S/m, a/R) are Holm's law:
// --isolated-necks selects it (the default flux-tube law is lower for large necks, docs/conduct.md).
TEST_F(ConductCli, LatticeAllAxesWritesSummaryAndFields) {
  const std::string in = lattice();
  const CliResult r = run(in + " --isolated-necks --axis all --phases LSM -o " + path("fields.h5") + " --json " + path("s.json") +
                    " --quiet --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(path("s.json"));
  for (const char* ax : {"x", "y", "z"}) {
    // Same 1e-6 criterion as the library test; the default tolerance is 1e-10.
    EXPECT_NEAR(s["sigma_eff"][ax].get<double>(), 2000.0, 2000.0 * 1e-6) << ax;
    EXPECT_NEAR(s["percolating_fraction"][ax].get<double>(), 1.0, 1e-12);
  }
  EXPECT_LT(s["residual"].get<double>(), 1e-9);
  EXPECT_GT(s["wall_time_s"].get<double>(), 0.0);
  EXPECT_TRUE(s.contains("sigma_eff_error"));
  EXPECT_EQ(s["network"]["nodes"].get<int>(), 80);
  EXPECT_TRUE(fs::exists(path("fields.xdmf")));
  h5::File f(path("fields.h5"), h5::File::Mode::read);
  EXPECT_EQ(f.read_double("/fields/x/potential").size(), 80u);
  EXPECT_EQ(f.read_double("/fields/z/current").size(), s["network"]["edges"].get<std::size_t>());
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "temporary left: " << e.path();
}

TEST_F(ConductCli, PeriodicTensor) {
  const std::string in = lattice(true);
  const CliResult r = run(in + " --isolated-necks --bc periodic --json " + path("s.json") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(path("s.json"));
  // Two phases with σ 1e4 and 1: every site is LSM (phase 0), so the tensor is 2000·I.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(s["sigma_tensor"][i][j].get<double>(), i == j ? 2000.0 : 0.0, 2000.0 * 1e-6);
}

// --neck-law selects the neck conductance (docs/conduct.md#neck-conductance). Periodic lattice of
// touching spheres R = 5 µm with bonds a = 1.1 R: every Laguerre face is the cube's square
// A = (2R)², d = R per side. Closed forms per edge, σ_eff = G/(2R):
//   isolated     Holm 2σa                          → σ_eff = σ a/R = 1.1e4 S/m
//   face_capped  min(2σa, σA/(2R)) = 2σR (binds)   → σ_eff = σ exactly (NetworkOptions::flux_tube
//                = false: the face's two-point flux caps Holm)
//   flux_tube    the disc πa² = 3.80 R² does not fill the face 4R²: the body and the tube's
//                constriction add resistance to d/(σA) per side → strictly below σ.
// --isolated-necks is the alias of --neck-law isolated; an unknown law or a contradiction exits 2.
TEST_F(ConductCli, NeckLawOptionSelectsEachLaw) {
  const std::string in = lattice(true, 5.5e-6);
  std::map<std::string, nlohmann::json> s;
  for (const std::string law : {"flux_tube", "face_capped", "isolated"}) {
    const CliResult r = run(in + " --neck-law " + law + " --bc periodic --json " + path(law + ".json") + " --quiet");
    ASSERT_EQ(r.code, 0) << law << ": " << r.err;
    s[law] = summary(path(law + ".json"));
  }
  const CliResult alias = run(in + " --isolated-necks --bc periodic --json " + path("alias.json") + " --quiet");
  ASSERT_EQ(alias.code, 0) << alias.err;
  EXPECT_EQ(s["flux_tube"]["neck_law"]["law"], "flux_tube");
  EXPECT_EQ(s["face_capped"]["neck_law"]["law"], "face_capped");
  EXPECT_EQ(s["isolated"]["neck_law"]["law"], "isolated_necks");
  EXPECT_EQ(summary(path("alias.json"))["neck_law"]["law"], "isolated_necks");
  for (const char* ax : {"x", "y", "z"}) {
    // 1e-6: the solver's default tolerance 1e-10 on a 80-node lattice.
    EXPECT_NEAR(s["isolated"]["sigma_eff"][ax].get<double>(), 1.1e4, 1.1e4 * 1e-6) << ax;
    EXPECT_NEAR(summary(path("alias.json"))["sigma_eff"][ax].get<double>(), 1.1e4, 1.1e4 * 1e-6) << ax;
    EXPECT_NEAR(s["face_capped"]["sigma_eff"][ax].get<double>(), 1e4, 1e4 * 1e-6) << ax;
    EXPECT_LT(s["flux_tube"]["sigma_eff"][ax].get<double>(), 1e4 * (1 - 1e-3)) << ax;
    EXPECT_GT(s["flux_tube"]["sigma_eff"][ax].get<double>(), 0.5e4) << ax;
  }
  // Every edge of the face-capped run is at its cap (below Holm).
  EXPECT_EQ(s["face_capped"]["neck_law"]["face_capped_edges"].get<std::size_t>(), s["face_capped"]["network"]["edges"].get<std::size_t>());
  CliResult bad = run(in + " --neck-law holm --json " + path("bad.json"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--neck-law"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("holm"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("bad.json")));
  bad = run(in + " --isolated-necks --neck-law face_capped --json " + path("bad.json"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--isolated-necks"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("bad.json")));
}

// The bounds are computed from the packing alone (union volume), not from the network: on the
// touching-sphere lattice φ = π/6 exactly, so HS = 2φ/(3 − φ) and Voigt = φ are hand values.
TEST_F(ConductCli, SummaryChecksTheHashinShtrikmanAndVoigtBounds) {
  const double phi = M_PI / 6, hs = 2 * phi / (3 - phi);
  {  // necks a = 0.2 R: σ/σ_s = a/R = 0.2 on every axis, under both bounds
    const std::string in = lattice(true);
    const CliResult r = run(in + " --isolated-necks --bc periodic --json " + path("s.json") + " --quiet");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto b = summary(path("s.json"))["bounds"];
    // 1e-9: the union volume of touching spheres is exact up to round-off in the power-cell clipping.
    EXPECT_NEAR(b["relative_density"].get<double>(), phi, 1e-9);
    EXPECT_NEAR(b["hs_upper_sigma_over_sigma_s"].get<double>(), hs, 1e-9);
    EXPECT_NEAR(b["voigt_sigma_over_sigma_s"].get<double>(), phi, 1e-9);
    EXPECT_DOUBLE_EQ(b["sigma_s"].get<double>(), 1e4);
    EXPECT_NEAR(b["mean_sigma_over_sigma_s"].get<double>(), 0.2, 1e-6);  // the solver's tolerance
    EXPECT_FALSE(b["bound_exceeded"].get<bool>());
  }
  {  // necks a = 0.98 R between spheres that only touch: Holm gives σ/σ_s = 0.98, more than
     // any body of density π/6 can conduct (the face cap, σ A/d = 10 µm σ per edge, does not bind)
    const std::string in = lattice(true, 4.9e-6);
    const CliResult r = run(in + " --isolated-necks --bc periodic --json " + path("s.json"));
    ASSERT_EQ(r.code, 0) << r.err;
    const auto b = summary(path("s.json"))["bounds"];
    EXPECT_NEAR(b["mean_sigma_over_sigma_s"].get<double>(), 0.98, 1e-6);
    EXPECT_TRUE(b["bound_exceeded"].get<bool>());
    EXPECT_NE(r.err.find("Hashin-Shtrikman upper bound"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("Voigt bound"), std::string::npos) << r.err;
  }
}

TEST_F(ConductCli, CompositeAndVoxelSections) {
  const std::string in = lattice();
  const CliResult r = run(in + " --electronic LSM --ionic YSZ --charge-transfer 1e3 --voxel-check 10,20,40 --json " +
                    path("s.json") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(path("s.json"));
  // No YSZ particle: the composite electrode has no path, reported, not an error.
  EXPECT_FALSE(s["composite"]["percolates"].get<bool>());
  EXPECT_EQ(s["voxel"]["runs"].size(), 3u);
  EXPECT_TRUE(s["voxel"].contains("extrapolated_sigma_eff"));
  // Per diameter (R = 5 µm spheres, 5 along x): 4 voxels per diameter is 20 along the 50 µm edge.
  const CliResult d = run(in + " --voxel-check 2d,4d --json " + path("d.json") + " --quiet");
  ASSERT_EQ(d.code, 0) << d.err;
  const auto sd = summary(path("d.json"));
  EXPECT_EQ(sd["voxel"]["resolution_unit"], "voxels per mean diameter");
  EXPECT_EQ(sd["voxel"]["runs"][1]["voxels_per_longest_edge"].get<int>(), 20);
  EXPECT_NEAR(sd["voxel"]["runs"][1]["voxels_per_diameter"].get<double>(), 4.0, 1e-9);
}

// The worked example of docs/conduct.md, command for command, on the example data shipped in
// data/examples (cathode.h5, made by tomodem-pack from cathode.yaml: LSM/YSZ 50/50 pressed to
// 100 MPa). Physics checks: 50 % LSM percolates along every axis; σ_eff stays below the parallel
// (Wiener) bound φ_LSM σ_LSM < 0.5 × 1e4 S/m; the composite electrode conducts.
TEST_F(ConductCli, DocsWorkedExampleRuns) {
  const std::string in = std::string(TOMODEM_TEST_DATA) + "/examples/cathode.h5";
  ASSERT_TRUE(fs::exists(in)) << in;
  CliResult r = run(in + " --phases LSM --axis all -o " + path("cathode-fields.h5") + " --json " + path("summary.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(path("summary.json"));
  for (const char* ax : {"x", "y", "z"}) {
    EXPECT_GT(s["sigma_eff"][ax].get<double>(), 0.0) << ax;
    EXPECT_LT(s["sigma_eff"][ax].get<double>(), 0.5e4) << ax;
  }
  EXPECT_TRUE(fs::exists(path("cathode-fields.xdmf")));
  r = run(in + " --phases LSM --bc periodic --json " + path("periodic.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(summary(path("periodic.json"))["sigma_tensor"].size(), 3u);
  r = run(in + " --phases LSM --axis z --electronic LSM --ionic YSZ --charge-transfer 1e3 --voxel-check 2d,4d,8d --json " +
          path("composite.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto c = summary(path("composite.json"));
  EXPECT_TRUE(c["composite"]["percolates"].get<bool>());
  EXPECT_GT(c["composite"]["resistance_ohm"].get<double>(), 0.0);
  EXPECT_EQ(c["voxel"]["runs"].size(), 3u);
  // The necks (median a/R ≈ 0.18) are not resolved at 8 voxels per diameter: the summary says so
  // and asks for more (q = a²/(R* h) >= 4 needs ~128 per diameter); the answers fall monotonically
  // (partial volumes) towards the network instead of jumping (153, 359, 267 S/m before issue 20).
  const auto& v = c["voxel"];
  EXPECT_FALSE(v["necks_resolved"].get<bool>());
  EXPECT_TRUE(v["warning"].get<bool>());
  EXPECT_GT(v["required_resolution_median_neck"].get<long>(), 8);
  const auto sv = v["sigma_eff_per_resolution"];
  EXPECT_GT(sv[0].get<double>(), sv[1].get<double>());
  EXPECT_GT(sv[1].get<double>(), sv[2].get<double>());
  EXPECT_GT(v["observed_order"].get<double>(), 0.5);
}

TEST_F(ConductCli, UnknownPhaseExitsTwoWithoutOutput) {
  const std::string in = lattice();
  const CliResult r = run(in + " --phases LSM,Nickel -o " + path("f.h5") + " --json " + path("s.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--phases"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Nickel"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("f.h5")));
  EXPECT_FALSE(fs::exists(path("s.json")));
}

TEST_F(ConductCli, NonPositiveConductivityNamesFileFieldValue) {
  // A YSZ layer (x = 0) with σ = -2: a phase with particles conducts by default and needs σ > 0.
  Packing p = network::test::sc_lattice(5, 4, 4, 5e-6, 1e-6, false, [](int x, int, int) { return x == 0 ? 1 : 0; });
  p.materials[0].name = "LSM";
  p.materials[0].conductivity = 1e4;
  p.materials[1].name = "YSZ";
  p.materials[1].conductivity = -2.0;
  const std::string in = path("lattice.h5");
  write_packing(in, p);
  const CliResult r = run(in + " -o " + path("f.h5") + " --json " + path("s.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(in), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("conductivity"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("f.h5")));
  EXPECT_FALSE(fs::exists(path("s.json")));
}

TEST_F(ConductCli, MissingOrEmptyNetworkExitsTwo) {
  EXPECT_EQ(run(path("missing.h5")).code, 2);
  Packing p = network::test::sc_lattice(3, 1, 1, 1.0, 0.1, false);
  p.bonds = BondTable{};
  for (auto& r : p.particles.radius) r = 0.5;  // far apart: no contact, no bond
  write_packing(path("sparse.h5"), p);
  const CliResult r = run(path("sparse.h5") + " --json " + path("s.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("empty network"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("s.json")));
}

// Keeps the bonds of p whose ends (positions) `drop` does not pick: a network cut by a plane.
static void drop_bonds(Packing& p, const std::function<bool(const Vec3&, const Vec3&)>& drop) {
  BondTable kept;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (drop(p.particles.position[p.bonds.i[b]], p.particles.position[p.bonds.j[b]])) continue;
    kept.i.push_back(p.bonds.i[b]);
    kept.j.push_back(p.bonds.j[b]);
    kept.radius.push_back(p.bonds.radius[b]);
    kept.rest_length.push_back(p.bonds.rest_length[b]);
    kept.state.push_back(p.bonds.state[b]);
    kept.broken_at.push_back(p.bonds.broken_at[b]);
  }
  p.bonds = kept;
}

TEST_F(ConductCli, NoPathIsReportedWithExitZero) {
  Packing p = network::test::sc_lattice(4, 2, 2, 1.0, 0.1, false);
  drop_bonds(p, [](const Vec3& a, const Vec3& b) { return (a.x - 4) * (b.x - 4) < 0; });  // across x = 4
  write_packing(path("cut.h5"), p);
  const CliResult r = run(path("cut.h5") + " --no-contacts --json " + path("s.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto s = summary(path("s.json"));
  EXPECT_EQ(s["sigma_eff"]["x"].get<double>(), 0.0);
  EXPECT_FALSE(s["percolates"].get<bool>());
  EXPECT_NE(r.err.find("no conducting path"), std::string::npos);
  // Periodic, cut across x only: x has no path and reports 0 exactly (the solve's round-off,
  // 2.4e-14 S/m, was reported beside a warning saying 0); y and z percolate.
  Packing q = network::test::sc_lattice(4, 4, 4, 1.0, 0.1, true);
  // Every bond along x goes: no path wraps in x.
  drop_bonds(q, [](const Vec3& a, const Vec3& b) { return std::abs(a.x - b.x) > 1e-9; });
  write_packing(path("cutp.h5"), q);
  const CliResult rp = run(path("cutp.h5") + " --no-contacts --bc periodic --json " + path("p.json"));
  ASSERT_EQ(rp.code, 0) << rp.err;
  const auto sp = summary(path("p.json"));
  EXPECT_EQ(sp["sigma_eff"]["x"].get<double>(), 0.0);
  EXPECT_EQ(sp["sigma_eff_error"]["x"].get<double>(), 0.0);
  EXPECT_GT(sp["sigma_eff"]["y"].get<double>(), 0.0);
  EXPECT_FALSE(sp["axes"]["x"]["percolates"].get<bool>());
  EXPECT_TRUE(sp["percolates"].get<bool>());  // some axis percolates (docs/conduct.md)
}
