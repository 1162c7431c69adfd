// tomodem-sinter --snapshots-at (issue 18): a green packing of tomodem-pack sintered freely once,
// one packing per target density with the necks as bonds; the union density of every snapshot is
// recomputed here by sampling the periodic cell on a grid (independent of the tool's power-cell
// clipping); targets the program cannot reach and bad lists are refused before anything runs.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tomodem/core/packing_io.hpp"
#include "tomodem/spatial/union_volume.hpp"

namespace fs = std::filesystem;

namespace {

struct Result {
  int code;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// 150 spheres of the study's powder (lognormal, median 1 µm), packed loosely to 0.5.
const std::string kGreen = R"(particles: 150
seed: 4
phases:
  - name: ceramic
    material: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 6000, conductivity: 1.0e4, surface_energy: 1.0}
    size_distribution: {kind: lognormal, diameter: 1.0e-6, sigma: 0.2, basis: volume}
contact: {normal: hertz, friction: 0.3, restitution: 0.3}
target: {solid_fraction: 0.5}
)";

// The study's program (pipelines/study/sinter.yaml); @HOLD@ is the hold at 1600 K, s.
const std::string kSettings = R"(physics: {tangential: viscous}
sintering:
  temperature:
    start: 300
    segments: [{rate: 50, to: 1600}, {hold: @HOLD@}]
  phases:
    - {material: ceramic, atomic_volume: 8.47e-30, boundary_diffusion: 8.6e-10, activation_energy: 418.0e3,
       dihedral_angle: 150, tangential_viscosity: 1.0}
  accuracy: {strain_per_step: @STRAIN@}
)";

std::string settings(const std::string& hold, const std::string& strain = "2.0e-5") {
  std::string s = kSettings;
  s.replace(s.find("@HOLD@"), 6, hold);
  return s.replace(s.find("@STRAIN@"), 8, strain);
}

// The study's pore-former family (pipelines/study/pore-former.yaml) at 100 particles: 20 % of the
// solid volume in formers three times the powder's size, packed to 0.5 and burnt out (macropores).
const std::string kPoreFormer = R"(particles: 100
seed: 1
phases:
  - name: ceramic
    volume_fraction: 0.8
    material: {youngs_modulus: 2.0e11, poisson_ratio: 0.3, density: 6000, conductivity: 1.0e4, surface_energy: 1.0}
    size_distribution: {kind: lognormal, diameter: 1.0e-6, sigma: 0.2, basis: volume}
  - name: pmma
    volume_fraction: 0.2
    pore_former: true
    material: {youngs_modulus: 3.0e9, poisson_ratio: 0.35, density: 1180}
    size_distribution: {kind: monodisperse, diameter: 3.0e-6}
contact: {normal: hertz, friction: 0.3, restitution: 0.3}
target: {solid_fraction: 0.5}
)";

/// Union volume fraction of the spheres in a periodic box (diagonal h) by sampling an n³ grid of
/// cell centres: each point is inside when some sphere (through the periodic images) holds it.
double grid_density(const tomodem::Packing& p, int n) {
  const double L[3] = {p.cell.h(0, 0), p.cell.h(1, 1), p.cell.h(2, 2)};
  // Bin the spheres on a coarse grid of m³ bins at least 2 r_max wide: a point's spheres lie in
  // its bin and the 26 around it.
  double rmax = 0;
  for (double r : p.particles.radius) rmax = std::max(rmax, r);
  int m[3];
  for (int k = 0; k < 3; ++k) m[k] = std::max(1, int(L[k] / (2 * rmax)));
  std::vector<std::vector<std::size_t>> bins(std::size_t(m[0] * m[1] * m[2]));
  auto wrap = [](double x, double l) { return x - l * std::floor(x / l); };
  auto bin_of = [&](const double x[3], int b[3]) {
    for (int k = 0; k < 3; ++k) b[k] = std::min(m[k] - 1, int(wrap(x[k] - p.cell.origin[k], L[k]) / L[k] * m[k]));
  };
  for (std::size_t i = 0; i < p.particles.size(); ++i) {
    const double x[3] = {p.particles.position[i].x, p.particles.position[i].y, p.particles.position[i].z};
    int b[3];
    bin_of(x, b);
    bins[std::size_t((b[0] * m[1] + b[1]) * m[2] + b[2])].push_back(i);
  }
  long inside = 0;
  for (int a = 0; a < n; ++a)
    for (int c = 0; c < n; ++c)
      for (int e = 0; e < n; ++e) {
        const double x[3] = {p.cell.origin.x + (a + 0.5) / n * L[0], p.cell.origin.y + (c + 0.5) / n * L[1],
                             p.cell.origin.z + (e + 0.5) / n * L[2]};
        int b[3];
        bin_of(x, b);
        bool in = false;
        for (int da = -1; da <= 1 && !in; ++da)
          for (int dc = -1; dc <= 1 && !in; ++dc)
            for (int de = -1; de <= 1 && !in; ++de) {
              const int q[3] = {(b[0] + da + m[0]) % m[0], (b[1] + dc + m[1]) % m[1], (b[2] + de + m[2]) % m[2]};
              for (std::size_t i : bins[std::size_t((q[0] * m[1] + q[1]) * m[2] + q[2])]) {
                double d2 = 0;
                const double y[3] = {p.particles.position[i].x, p.particles.position[i].y, p.particles.position[i].z};
                for (int k = 0; k < 3; ++k) {
                  double d = x[k] - y[k];
                  d -= L[k] * std::round(d / L[k]);
                  d2 += d * d;
                }
                const double r = p.particles.radius[i];
                if (d2 < r * r) {
                  in = true;
                  break;
                }
              }
            }
        inside += in;
      }
  return double(inside) / (double(n) * n * n);
}

class SinterSnapshots : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("tomodem_sinter_snap_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "green.yaml") << kGreen;
    const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem-pack " + (dir / "green.yaml").string() + " -o " +
                            (dir / "green.h5").string() + " --no-tessellation -q --threads 1 --json " +
                            (dir / "pack.json").string() + " 2> " + (dir / "pack.err").string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir / "pack.err");
  }
  void TearDown() override { fs::remove_all(dir); }
  Result sinter(const std::string& hold, const std::string& args, const std::string& strain = "2.0e-5",
                const std::string& green = "green.h5") {
    std::ofstream(dir / "sinter.yaml") << settings(hold, strain);
    const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem-sinter " + (dir / green).string() +
                            " --sinter-config " + (dir / "sinter.yaml").string() + " --output-dir " +
                            (dir / "out").string() + " --no-plot --threads 1 -q " + args + " > " +
                            (dir / "stdout.txt").string() + " 2> " + (dir / "stderr.txt").string();
    const int status = std::system(cmd.c_str());
    return {WEXITSTATUS(status), slurp(dir / "stdout.txt"), slurp(dir / "stderr.txt")};
  }
  fs::path dir;
};

}  // namespace

TEST_F(SinterSnapshots, OneRunWritesEachTargetDensityWithItsNecksAsBonds) {
  const Result r = sinter("1.0e6", "--snapshots-at 0.55,0.6,0.65");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  // The run stops at the last snapshot (the hold is 10^6 s long).
  EXPECT_EQ(j["stop_reason"], "target_density");
  ASSERT_EQ(j["snapshots"].size(), 3u);
  const double targets[3] = {0.55, 0.6, 0.65};
  const char* names[3] = {"snapshot-0.55.h5", "snapshot-0.6.h5", "snapshot-0.65.h5"};
  long last_step = 0;
  for (int k = 0; k < 3; ++k) {
    const auto& s = j["snapshots"][std::size_t(k)];
    // One run: the snapshots follow each other in steps and time.
    EXPECT_GT(s["step"].get<long>(), last_step);
    last_step = s["step"].get<long>();
    // The density is checked every 10 steps; a step densifies by at most 3 rho strain_per_step
    // (2e-5): 4e-4 per check at 0.65, so a snapshot lies within [target, target + 1e-3].
    const double rho = s["relative_density"].get<double>();
    EXPECT_GE(rho, targets[k]);
    EXPECT_LE(rho, targets[k] + 1e-3);
    const fs::path f = dir / "out" / names[k];
    ASSERT_TRUE(fs::exists(f)) << f;
    EXPECT_EQ(s["file"].get<std::string>(), f.string());
    const tomodem::Packing p = tomodem::read_packing(f.string());
    ASSERT_EQ(p.particles.size(), 150u);
    // Free sintering deforms the cell along its axes only.
    EXPECT_NEAR(p.cell.h(0, 1), 0, 1e-12);
    EXPECT_NEAR(p.cell.h(1, 2), 0, 1e-12);
    // Independent union density: a 160³ grid (spacing about 0.07 µm against radii of 0.5 µm);
    // midpoint sampling of a volume bounded by sphere caps errs by well under 2e-3 here (checked
    // below: the grid agrees with the tool's exact union to that on every snapshot).
    EXPECT_NEAR(grid_density(p, 160), rho, 2e-3) << names[k];
    // Necks as bonds: one per sintering contact, the pair overlapping, a neck radius below the
    // smaller sphere's, as many as the summary counts.
    ASSERT_EQ(p.bonds.size(), s["bonds"].get<std::size_t>());
    ASSERT_GT(p.bonds.size(), 150u);
    const double L[3] = {p.cell.h(0, 0), p.cell.h(1, 1), p.cell.h(2, 2)};
    for (std::size_t b = 0; b < p.bonds.size(); ++b) {
      const std::size_t i = std::size_t(p.bonds.i[b]), jj = std::size_t(p.bonds.j[b]);
      tomodem::Vec3 d = p.particles.position[jj] - p.particles.position[i];
      for (int c = 0; c < 3; ++c) d[c] -= L[c] * std::round(d[c] / L[c]);
      const double dist = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
      EXPECT_LT(dist, p.particles.radius[i] + p.particles.radius[jj]);
      EXPECT_NEAR(dist, p.bonds.rest_length[b], 1e-9 * L[0]);
      EXPECT_GT(p.bonds.radius[b], 0);
    }
    // Bonds per particle grow with density (the network densifies, necks are added).
    if (k > 0) EXPECT_GT(s["bonds"].get<long>(), j["snapshots"][std::size_t(k - 1)]["bonds"].get<long>());
  }
  // The final packing is the last snapshot's state (the run stopped there).
  EXPECT_NEAR(j["relative_density"].get<double>(), j["snapshots"][2]["relative_density"].get<double>(), 1e-12);
}

// A curve row evaluates the density too, between the checks (every update_interval steps): when a
// row is the first to find the last snapshot's density, the run stops there and must take the
// snapshot (it stopped without it and exited 2, "the program ends below the snapshot density",
// on replica 64 of the study). Rows every ~0.1 s of sintering time (a step is ~1 s) and a check
// every 50 steps make a row find each density first.
TEST_F(SinterSnapshots, ARowThatReachesTheLastDensityTakesItsSnapshot) {
  std::string extra = settings("1.0e5");
  const std::string accuracy = "accuracy: {strain_per_step: 2.0e-5}";
  extra.replace(extra.find(accuracy), accuracy.size(),
                "accuracy: {strain_per_step: 2.0e-5, update_interval: 50}\n  output: {rows: 1000000}");
  std::ofstream(dir / "rows.yaml") << extra;
  const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem-sinter " + (dir / "green.h5").string() +
                          " --sinter-config " + (dir / "rows.yaml").string() + " --output-dir " + (dir / "out").string() +
                          " --no-plot --threads 1 -q --snapshots-at 0.55,0.6 > " + (dir / "stdout.txt").string() +
                          " 2> " + (dir / "stderr.txt").string();
  const int status = std::system(cmd.c_str());
  ASSERT_EQ(WEXITSTATUS(status), 0) << slurp(dir / "stderr.txt");
  const auto j = nlohmann::json::parse(slurp(dir / "stdout.txt"));
  EXPECT_EQ(j["stop_reason"], "target_density");
  ASSERT_EQ(j["snapshots"].size(), 2u);
  const double targets[2] = {0.55, 0.6};
  for (int k = 0; k < 2; ++k) {
    // A row is due every step, so the density is seen within one step (< 1e-4 at 2e-5 strain).
    const double rho = j["snapshots"][std::size_t(k)]["relative_density"].get<double>();
    EXPECT_GE(rho, targets[k]);
    EXPECT_LE(rho, targets[k] + 2e-4);
  }
  EXPECT_TRUE(fs::exists(dir / "out" / "snapshot-0.6.h5"));
}

TEST_F(SinterSnapshots, UnreachableOrBadTargetsAreRefusedBeforeAnythingRuns) {
  // A 10 s hold: two free spheres shrink by about 1 %, so the packing reaches about 0.52 from
  // 0.50 (the estimate from above; measured on the study's 500-sphere packing: estimate 0.4724,
  // run 0.4706 from 0.45). 0.9 is refused naming the settings file, the program's line and the estimate.
  Result r = sinter("10", "--snapshots-at 0.55,0.9");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("sinter.yaml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("sintering.temperature (line 3)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("reaches about"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("0.9"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  // Not ascending, at or below the green density, not a density.
  for (const char* bad : {"0.6,0.55", "0.3,0.6", "0.6,abc", "1.2"}) {
    r = sinter("1.0e6", std::string("--snapshots-at ") + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--snapshots-at"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << bad;
  }
  r = sinter("1.0e6", "--snapshots-at 0.6 --snapshot-name out.h5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("{density}"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// Mass conservation (issue 18 item 7, docs/sintering.md "Mass conservation"): the pore-former
// family sintered freely to 0.9, where the matrix between the macropores reaches full density and
// nearly enclosed spheres cannot hold their volume by growing. At each snapshot the union density
// of the written packing (exact power-cell union) must equal the mass-conserving density ρ₀V₀/V,
// with ρ₀ the union density of the green packing and V₀, V the two files' cell volumes (before the
// fix: 1.174 at union 0.9 on the study's 500 particles). The same with a strain step 4 times
// larger (8e-5 against the study's 2e-5): the result must not hang on the step. Tolerance: the
// tool's kMassTolerance, 1e-3 (the residual of its Newton update is second order, measured
// 1.2e-4 at most on the study's 500-particle runs).
TEST_F(SinterSnapshots, PoreFormerRunConservesMassAtAnyStrainStep) {
  std::ofstream(dir / "pore.yaml") << kPoreFormer;
  const std::string pack = std::string(TOMODEM_BIN_DIR) + "/tomodem-pack " + (dir / "pore.yaml").string() + " -o " +
                           (dir / "pore.h5").string() + " --no-tessellation -q --threads 1 2> " +
                           (dir / "pack.err").string();
  ASSERT_EQ(std::system(pack.c_str()), 0) << slurp(dir / "pack.err");
  const tomodem::Packing green = tomodem::read_packing((dir / "pore.h5").string());
  const double rho0 = tomodem::spatial::union_relative_density(green.particles.position, green.particles.radius, green.cell);
  const double V0 = green.cell.volume();
  const double targets[4] = {0.6, 0.7, 0.8, 0.9};
  for (const char* strain : {"2.0e-5", "8.0e-5"}) {
    fs::remove_all(dir / "out");
    const Result r = sinter("1.0e6", "--snapshots-at 0.6,0.7,0.8,0.9", strain, "pore.h5");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_TRUE(j["mass_conserved"].get<bool>()) << strain << ": " << j["max_mass_mismatch"];
    EXPECT_EQ(r.err.find("mass not conserved"), std::string::npos) << r.err;
    ASSERT_EQ(j["snapshots"].size(), 4u);
    for (int k = 0; k < 4; ++k) {
      const auto& s = j["snapshots"][std::size_t(k)];
      const tomodem::Packing p = tomodem::read_packing(s["file"].get<std::string>());
      const double rho = tomodem::spatial::union_relative_density(p.particles.position, p.particles.radius, p.cell);
      const double cell = rho0 * V0 / p.cell.volume();
      std::printf("strain %s, snapshot %.1f: union %.5f, rho0 V0/V %.5f, Z %.2f\n", strain, targets[k], rho, cell,
                  s["coordination"].get<double>());
      EXPECT_GE(rho, targets[k]);
      EXPECT_NEAR(rho / cell, 1.0, 1e-3) << "strain " << strain << " at " << targets[k];
    }
  }
}
