// tomodem-fracture from the command line: outputs and summary keys, K_IC from the peak with the
// geometry factor of docs/physics.md#fracture-toughness, and bad input (exit 2, no output at all).
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
#include <tuple>

#include "../../validation/fracture/samples.hpp"
#include "../common/tool_test.hpp"
#include "tomodem/core/h5.hpp"

namespace fs = std::filesystem;
using namespace tomodem;

namespace {
class FractureCli : public tomodem::test::ToolTest {
 protected:
  FractureCli() : ToolTest("tomodem-fracture-e2e") {}
  /// The exit code of `tomodem-fracture args` and its stderr.
  std::pair<int, std::string> run(const std::string& args) const {
    const int code = sh(bin("tomodem-fracture") + " " + args);
    return {code, text("stderr.txt")};
  }
  std::string network(mechanics::Network net) const {
    mechanics::write_network(path("net.h5"), net);
    return path("net.h5");
  }
  std::string outputs() const {
    return " --json " + path("out.json") + " --curve " + path("curve.csv") + " --map " + path("map.h5") + " -q";
  }
  void expect_no_output() const {
    for (const char* f : {"out.json", "curve.csv", "map.h5", "map.xdmf"}) EXPECT_FALSE(fs::exists(path(f))) << f;
  }
};
}  // namespace

TEST_F(FractureCli, SlaAndExplicitWriteCurveMapAndSummary) {
  const mechanics::Network net = mechanics::test::slab(12, 3, 18, 11);
  const std::string in = network(net);
  auto [code, err] = run(in + " --method both --a-over-w 0.2 --stop-fraction 0.5 --no-elastic" + outputs());
  ASSERT_EQ(code, 0) << err;
  const auto j = json("out.json");
  for (const char* key : {"K_IC", "K_IC_error", "peak_stress", "crack_length", "broken_bonds", "wall_time_s"})
    EXPECT_TRUE(j.contains(key)) << key;
  // K_IC = Y σ sqrt(πa), Y = sqrt(sec(πa/W)) (docs/physics.md#fracture-toughness, centre crack), σ = peak force / (W B).
  const double a = j["crack_length"], W = j["width"], B = j["thickness"];
  const double sigma = j["peak_force"].get<double>() / (W * B);
  EXPECT_NEAR(j["peak_stress"].get<double>() / sigma, 1.0, 1e-12);
  EXPECT_NEAR(a / W, 0.2, 1e-12);
  EXPECT_NEAR(j["K_IC"].get<double>() / (std::sqrt(1 / std::cos(M_PI * a / W)) * sigma * std::sqrt(M_PI * a)), 1.0, 1e-12);
  EXPECT_GT(j["broken_bonds"].get<long>(), 0);
  // K_IC_error of the SLA (the primary method, no dynamic part): the crack tip is known to ± half
  // a bond length l, δK/K = (d ln K/da) l/2 with d ln K/da = 1/(2a) + π tan(πa/W)/(2W) for
  // Y = sqrt(sec(πa/W)) (docs/fracture.md). l is the mean length of the load bonds, which lies
  // between the shortest and the longest bond of the network.
  double lmin = 1e300, lmax = 0;
  for (double l : net.packing.bonds.rest_length) lmin = std::min(lmin, l), lmax = std::max(lmax, l);
  ASSERT_GT(lmax, 0);
  const double dlnK_da = 1 / (2 * a) + M_PI * std::tan(M_PI * a / W) / (2 * W);
  EXPECT_GE(j["K_IC_error"].get<double>(), dlnK_da * 0.5 * lmin * (1 - 1e-9));
  EXPECT_LE(j["K_IC_error"].get<double>(), dlnK_da * 0.5 * lmax * (1 + 1e-9));
  // ... and independent between samples: random, so a report over replicas does not add it again.
  EXPECT_EQ(j["K_IC_error_kind"], "random");
  EXPECT_TRUE(j.contains("explicit_vs_sla"));
  // The curve: header and rising then falling load.
  std::ifstream csv(path("curve.csv"));
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "opening_m,force_N,broken_bonds");
  EXPECT_TRUE(fs::exists(path("curve_explicit.csv")));
  // The map: bonds coloured by state, particles by broken bonds, one broken bond per event.
  ASSERT_TRUE(fs::exists(path("map.xdmf")));
  h5::File m(path("map.h5"), h5::File::Mode::read);
  const auto state = m.read_int32("/bonds/state");
  const auto per = m.read_int32("/particles/broken_bonds");
  long broken = 0, ends = 0;
  for (int s : state) broken += s == 1 || s == 2;
  for (int c : per) ends += c;
  EXPECT_EQ(broken, j["broken_bonds"].get<long>());
  EXPECT_EQ(ends, 2 * broken);
}

// An explicit test stopped by --max-steps recorded only stop_reason "--max-steps reached" and exited
// 0, its K_IC reported as if the load had fallen past the peak. Like young's explicit test at
// --max-steps it now says so: explicit.max_steps_reached true, target_reached false, a warning
// naming the opening and load reached, exit 4, the outputs written. A cap under two records of the
// load is refused before any run (the SLA's too, with --method both): exit 2 naming --max-steps.
TEST_F(FractureCli, ExplicitTestStoppedByMaxStepsIsReportedShort) {
  const std::string in = network(mechanics::test::slab(12, 3, 18, 11));
  const std::string args = in + " --method explicit --a-over-w 0.2 --stop-fraction 0.5 --no-elastic --no-energy --threads 1";
  auto [code, err] = run(args + " --json " + path("full.json"));
  ASSERT_EQ(code, 0) << err;
  const auto full = json("full.json");
  EXPECT_FALSE(full["explicit"]["max_steps_reached"].get<bool>());
  EXPECT_TRUE(full["target_reached"].get<bool>());
  const long steps = full["explicit"]["steps"].get<long>();
  ASSERT_GT(steps, 8);
  // Half the steps: the load has not yet fallen below half its peak (the full run stops at the
  // first record where it has).
  const std::string cap = std::to_string(steps / 2);
  std::tie(code, err) = run(args + " --max-steps " + cap + " --json " + path("short.json") + " --curve " + path("short.csv"));
  ASSERT_EQ(code, 4) << err;  // the README's code for a run that ends short of what was asked
  const auto j = json("short.json");
  EXPECT_TRUE(j["explicit"]["max_steps_reached"].get<bool>());
  EXPECT_FALSE(j["target_reached"].get<bool>());
  EXPECT_EQ(j["explicit"]["stop_reason"], "--max-steps reached");
  EXPECT_LE(j["explicit"]["steps"].get<long>(), steps / 2);
  EXPECT_GT(j["K_IC"].get<double>(), 0);
  EXPECT_NE(err.find("--max-steps " + cap + " reached"), std::string::npos) << err;
  EXPECT_NE(err.find("target_reached: false"), std::string::npos) << err;
  EXPECT_TRUE(fs::exists(path("short.csv")));
  // One step: not two records of the load; refused before the run (with both, before the SLA).
  for (const char* method : {"explicit", "both"}) {
    std::tie(code, err) = run(in + " --method " + method + " --a-over-w 0.2 --no-elastic --max-steps 1 --json " + path("out.json") +
                                 " --curve " + path("curve.csv") + " --map " + path("map.h5"));  // no -q: the SLA would say it starts
    EXPECT_EQ(code, 2) << method << ": " << err;
    EXPECT_NE(err.find("--max-steps"), std::string::npos) << err;
    EXPECT_NE(err.find("two records"), std::string::npos) << err;
    EXPECT_EQ(err.find("sequentially linear"), std::string::npos) << err;  // the SLA did not start
    expect_no_output();
  }
}

TEST_F(FractureCli, CrackLongerThanSampleExits2WithoutOutput) {
  const std::string in = network(mechanics::test::slab(12, 3, 18, 11));
  auto [c1, e1] = run(in + " --geometry edge --a-over-w 1.2" + outputs());
  EXPECT_EQ(c1, 2) << e1;
  EXPECT_NE(e1.find("a/W must lie in (0, 0.6]"), std::string::npos) << e1;
  auto [c2, e2] = run(in + " --geometry centre --a-over-w 0.5" + outputs());
  EXPECT_EQ(c2, 2) << e2;
  // Inside the sample but past where the geometry factor holds (Tada: a/W <= 0.6 for an edge
  // notch, 2a/W <= 0.7 for a centre crack): K_IC would carry an unknown bias.
  auto [c3, e3] = run(in + " --geometry edge --a-over-w 0.7" + outputs());
  EXPECT_EQ(c3, 2) << e3;
  auto [c4, e4] = run(in + " --geometry centre --a-over-w 0.4" + outputs());
  EXPECT_EQ(c4, 2) << e4;
  EXPECT_NE(e4.find("2a/W <= 0.7"), std::string::npos) << e4;
  expect_no_output();
}

TEST_F(FractureCli, MissingStrengthsExit2WithoutOutput) {
  const std::string in = network(mechanics::test::slab(12, 3, 18, 11, mechanics::test::alumina(100e9, 0.25, 3000, 0.0)));
  auto [c1, e1] = run(in + " --criterion stress --tensile-strength 1e8" + outputs());
  EXPECT_EQ(c1, 2) << e1;
  EXPECT_NE(e1.find("--shear-strength"), std::string::npos) << e1;
  auto [c2, e2] = run(in + " --criterion lefm" + outputs());  // surface energy 0 in the file
  EXPECT_EQ(c2, 2) << e2;
  EXPECT_NE(e2.find("surface_energy"), std::string::npos) << e2;
  expect_no_output();
}

// A material no bonded particle uses (a pore former's, whose particles were removed after packing)
// needs no surface energy: the same network with such a second material runs, with the same K_IC.
TEST_F(FractureCli, UnbondedMaterialNeedsNoSurfaceEnergy) {
  mechanics::Network net = mechanics::test::slab(12, 3, 18, 11);
  auto [c0, e0] = run(network(net) + " --a-over-w 0.2 --stop-fraction 0.5 --no-elastic" + outputs());
  ASSERT_EQ(c0, 0) << e0;
  const double k0 = json("out.json")["K_IC"];
  Material pore_former = mechanics::test::alumina(3e9, 0.35, 1190, 0.0);
  pore_former.name = "pore_former";
  net.packing.materials.push_back(pore_former);
  auto [c1, e1] = run(network(net) + " --a-over-w 0.2 --stop-fraction 0.5 --no-elastic" + outputs());
  ASSERT_EQ(c1, 0) << e1;
  EXPECT_EQ(json("out.json")["K_IC"].get<double>(), k0);
}

TEST_F(FractureCli, NoBondsAcrossTheCrackPathExit2WithoutOutput) {
  mechanics::Network net = mechanics::test::slab(12, 3, 18, 11);
  Packing& p = net.packing;
  // Break every bond that crosses the mid-plane of the particle centres (where the crack goes).
  double zmin = 1e300, zmax = -1e300;
  for (const Vec3& x : p.particles.position) zmin = std::min(zmin, x.z), zmax = std::max(zmax, x.z);
  const double zc = 0.5 * (zmin + zmax);
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const double zi = p.particles.position[p.bonds.i[b]].z;
    const double zj = zi + mechanics::bond_vector(p, net.image[b], b).z;
    if ((zi - zc) * (zj - zc) < 0) p.bonds.state[b] = BondTable::broken;
  }
  const std::string in = network(net);
  auto [code, err] = run(in + outputs());
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("no bonds across the crack path"), std::string::npos) << err;
  expect_no_output();
}

namespace {
/// The network with its axes turned cyclically, written out case by case (independent of the
/// tool's permute_axes): turns = 1 puts the old x along z, (x, y, z) -> (y, z, x); turns = 2 puts
/// the old y along z, (x, y, z) -> (z, x, y). The cells of these tests are boxes at the origin.
mechanics::Network turned(const mechanics::Network& net, int turns) {
  const auto turn = [turns](const Vec3& v) {
    return turns == 0 ? v : turns == 1 ? Vec3{v.y, v.z, v.x} : Vec3{v.z, v.x, v.y};
  };
  mechanics::Network out = net;
  for (Vec3& x : out.packing.particles.position) x = turn(x);
  const Vec3 L = turn({net.packing.cell.h(0, 0), net.packing.cell.h(1, 1), net.packing.cell.h(2, 2)});
  out.packing.cell = Cell::box({0, 0, 0}, L, true);
  for (auto& im : out.image) {
    const Vec3 t = turn({double(im[0]), double(im[1]), double(im[2])});
    im = {int32_t(t.x), int32_t(t.y), int32_t(t.z)};
  }
  return out;
}

/// The network moved by k/K of its cell along x and z: where the tool puts its k-th of K cracks.
mechanics::Network moved(mechanics::Network net, int k, int K) {
  const Vec3 shift{double(k) / K * net.packing.cell.h(0, 0), 0.0, double(k) / K * net.packing.cell.h(2, 2)};
  for (Vec3& x : net.packing.particles.position) x = x + shift;
  return net;
}

/// Mean and sample standard deviation (n − 1) of three or more values, as the summary computes them
/// (written out here, not mechanics::mean_sem, so the test checks the tool against its own arithmetic).
std::pair<double, double> mean_sd(const std::vector<double>& v) {
  double mean = 0, ss = 0;
  for (double x : v) mean += x / double(v.size());
  for (double x : v) ss += (x - mean) * (x - mean);
  return {mean, std::sqrt(ss / double(v.size() - 1))};
}

/// Simple cubic lattice, spacing d, n × n × n sites half a spacing from the cell faces (a site on a
/// face could wrap to either side after a move), every touching pair bonded.
mechanics::Network cubic_lattice(int n, double d) {
  mechanics::Network net;
  net.packing = mechanics::test::lattice("simple_cubic", n, d, 0.6 * d, mechanics::test::alumina());
  for (Vec3& x : net.packing.particles.position) x = x + Vec3{0.5 * d, 0.5 * d, 0.5 * d};
  mechanics::test::bond_ratio(net, 1.0);
  return net;
}
}  // namespace

// --cracks K on a simple cubic lattice (every bond alike, spacing d, 8 d cell): a cyclic turn of
// the axes and a move by 2 d along x and z map the lattice onto itself, so each of the K = 4
// cracks (loaded along z, x, y, z by default) sees the same sample and must give the single-crack
// K_IC. Tolerance 1e-9: the same systems with the particles numbered differently (round-off of
// the solve order; the lattice's tied bonds break as one group).
TEST_F(FractureCli, CracksOnALatticeAllGiveTheSingleCrackValue) {
  const std::string in = network(cubic_lattice(8, 2e-6)), opts = " --a-over-w 0.22 --no-elastic --json " + path("out.json") + " -q";
  auto [c1, e1] = run(in + opts);
  ASSERT_EQ(c1, 0) << e1;
  const auto one = json("out.json");
  auto [c4, e4] = run(in + opts + " --cracks 4");
  ASSERT_EQ(c4, 0) << e4;
  const auto four = json("out.json");
  const double K1 = one["K_IC"], e1rel = one["K_IC_error"];
  ASSERT_EQ(four["cracks"]["K_IC"].size(), 4u);
  EXPECT_EQ(four["cracks"]["orientations"], "three");
  EXPECT_EQ(four["cracks"]["load_axis"], nlohmann::json({"z", "x", "y", "z"}));
  EXPECT_EQ(four["cracks"]["shift"], nlohmann::json({0.0, 0.25, 0.5, 0.75}));
  for (double K : four["cracks"]["K_IC"]) EXPECT_NEAR(K / K1, 1.0, 1e-9);
  for (const char* axis : {"x", "y", "z"}) EXPECT_NEAR(four["cracks"]["mean_by_load_axis"][axis].get<double>() / K1, 1.0, 1e-9);
  EXPECT_NEAR(four["K_IC"].get<double>() / K1, 1.0, 1e-9);
  EXPECT_LT(four["cracks"]["sd"].get<double>(), 1e-9 * K1);
  // No spread: the uncertainty is the method's alone, its relative error / sqrt(4) (docs/fracture.md).
  EXPECT_NEAR(four["K_IC_error"].get<double>() / (e1rel / 2), 1.0, 1e-6);
}

// --cracks 3 on a random network (8 d cube, three orientations by default): crack k is the
// single-crack test of the network with its axes turned k times and moved by k/3 of the turned
// cell along x and z. The test turns and moves the network itself, runs one crack on each file
// and checks the per-crack values (same arithmetic: 1e-12), their mean, the means by load axis,
// sd, standard error and the combined error sqrt(sem² + Σ(e_k K_k)²/K²)/mean from those values.
// With --method both the explicit test runs on every crack too and the methods are compared
// crack by crack: each pair must be the single-crack run's (1e-9), and the mean and standard
// error of the paired differences are recomputed from those runs.
TEST_F(FractureCli, CracksAreSingleCrackRunsOnTheTurnedAndMovedNetwork) {
  const mechanics::Network net = mechanics::test::slab(8, 8, 8, 11);
  const std::string opts = " --a-over-w 0.2 --no-elastic --method both --no-energy --json " + path("out.json") + " -q";
  auto [c3, e3] = run(network(net) + opts + " --cracks 3");
  ASSERT_EQ(c3, 0) << e3;
  const auto three = json("out.json");
  EXPECT_EQ(three["cracks"]["load_axis"], nlohmann::json({"z", "x", "y"}));
  std::vector<double> K, e, d;
  for (int k = 0; k < 3; ++k) {
    auto [c, err] = run(network(moved(turned(net, k), k, 3)) + opts);
    ASSERT_EQ(c, 0) << err;
    K.push_back(json("out.json")["K_IC"]);
    e.push_back(json("out.json")["K_IC_error"]);
    EXPECT_NEAR(three["cracks"]["K_IC"][k].get<double>() / K.back(), 1.0, 1e-12) << "crack " << k;
    EXPECT_NEAR(three["cracks"]["mean_by_load_axis"]["zxy"[k] + std::string()].get<double>() / K.back(), 1.0, 1e-12);
    const auto one = json("out.json");
    d.push_back(one["explicit_vs_sla"]);
    EXPECT_NEAR(three["cracks"]["explicit_vs_sla"][k].get<double>(), d.back(), 1e-9) << "crack " << k;
    EXPECT_NEAR(three["cracks"]["explicit_K_IC"][k].get<double>() / one["explicit"]["K_IC"].get<double>(), 1.0, 1e-9);
  }
  EXPECT_EQ(three["cracks"]["explicit_vs_sla"][0], three["explicit_vs_sla"]);  // crack 0 is the top-level pair
  const auto [dmean, dsd] = mean_sd(d);
  EXPECT_NEAR(three["cracks"]["explicit_vs_sla_mean"].get<double>(), dmean, 1e-12);
  EXPECT_NEAR(three["cracks"]["explicit_vs_sla_sem"].get<double>(), dsd / std::sqrt(3.0), 1e-12);
  const auto [mean, sd] = mean_sd(K);
  double method = 0;
  for (int k = 0; k < 3; ++k) method += std::pow(e[k] * K[k], 2);
  const double sem = sd / std::sqrt(3.0);
  EXPECT_GT(sd, 0.01 * mean);  // three different places and axes in a random network: the cracks differ
  EXPECT_NEAR(three["K_IC"].get<double>() / mean, 1.0, 1e-12);
  EXPECT_NEAR(three["cracks"]["sd"].get<double>() / sd, 1.0, 1e-9);
  EXPECT_NEAR(three["cracks"]["sem"].get<double>() / sem, 1.0, 1e-9);
  EXPECT_NEAR(three["K_IC_error"].get<double>() / (std::sqrt(sem * sem + method / 9) / mean), 1.0, 1e-9);
}

// --crack-orientations one is the behaviour before the three orientations: crack k is the
// single-crack test of the network moved by k/3 of the cell along x and z, loaded along z. The
// same operations on the same numbers, so the values are equal exactly.
TEST_F(FractureCli, OneOrientationIsTheMovedNetworkAlongZ) {
  const mechanics::Network net = mechanics::test::slab(12, 3, 18, 11);
  const std::string opts = " --a-over-w 0.2 --no-elastic --json " + path("out.json") + " -q";
  auto [c3, e3] = run(network(net) + opts + " --cracks 3 --crack-orientations one");
  ASSERT_EQ(c3, 0) << e3;
  const auto three = json("out.json");
  EXPECT_EQ(three["cracks"]["orientations"], "one");
  EXPECT_EQ(three["cracks"]["load_axis"], nlohmann::json({"z", "z", "z"}));
  EXPECT_EQ(three["cracks"]["mean_by_load_axis"].size(), 1u);
  EXPECT_EQ(three["cracks"]["mean_by_load_axis"]["z"], three["K_IC"]);
  for (int k = 0; k < 3; ++k) {
    auto [c, err] = run(network(moved(net, k, 3)) + opts);
    ASSERT_EQ(c, 0) << err;
    EXPECT_EQ(three["cracks"]["K_IC"][k].get<double>(), json("out.json")["K_IC"].get<double>()) << "crack " << k;
  }
}

// An orthotropic lattice: simple cubic (spacing d, so the three samples have the same geometry
// and the same crack-tip discreteness) with the neck radius of the bonds along x, y, z in the
// ratio 0.8 : 0.6 : 1. A crack loaded along axis i cuts the bonds along i, one per d²: G_c =
// Γ π a_i² / d²; the stiffness along i is carried by the same bonds in series, E_i ∝ E_b π a_i² / d²
// (no Poisson coupling on a cubic lattice under uniaxial load). LEFM K_IC = sqrt(E' G_c) ∝ a_i², so
// K_z > K_x > K_y, and the tool's mean is the mean of the three. The other bonds' shear stiffness
// enters E' of an orthotropic solid, so the ratios are not exactly (a_i/a_j)²: only the order is checked.
TEST_F(FractureCli, OrthotropicLatticeOrdersTheThreeOrientations) {
  const double d = 2e-6, scale[3] = {0.8, 0.6, 1.0};
  mechanics::Network net = cubic_lattice(8, d);
  Packing& p = net.packing;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const Vec3 v = mechanics::bond_vector(p, net.image[b], b);
    const int axis = std::abs(v.x) > 0.5 * d ? 0 : std::abs(v.y) > 0.5 * d ? 1 : 2;
    p.bonds.radius[b] = 0.3 * d * scale[axis];  // 0.3 d: pi a^2 < d^2, below any cap at the square Laguerre face
  }
  auto [c, err] = run(network(net) + " --a-over-w 0.22 --no-elastic --cracks 3 --json " + path("out.json") + " -q");
  ASSERT_EQ(c, 0) << err;
  const auto j = json("out.json");
  const auto& by = j["cracks"]["mean_by_load_axis"];
  const double Kx = by["x"], Ky = by["y"], Kz = by["z"];
  std::printf("K_IC along x %.4g, y %.4g, z %.4g Pa m^0.5: x/z %.3f (a^2 ratio 0.64), y/z %.3f (0.36)\n", Kx, Ky, Kz,
              Kx / Kz, Ky / Kz);
  EXPECT_GT(Kz, Kx);
  EXPECT_GT(Kx, Ky);
  EXPECT_NEAR(j["K_IC"].get<double>() / ((Kx + Ky + Kz) / 3), 1.0, 1e-12);  // the same three numbers summed
}

// Several cracks need a cell periodic along every axis: the cracks are cut in networks moved along
// x and z, and with three orientations each axis becomes z in turn.
TEST_F(FractureCli, CracksNeedAPeriodicCell) {
  mechanics::Network net = mechanics::test::slab(12, 3, 18, 11);
  net.packing.cell.periodic[0] = false;
  const std::string in = network(net);
  auto [code, err] = run(in + " --cracks 2 --no-elastic" + outputs());
  EXPECT_EQ(code, 2) << err;
  for (const char* word : {"--cracks 2", "/cell/periodic", "x not periodic", "along z, x and y", "--crack-orientations one"})
    EXPECT_NE(err.find(word), std::string::npos) << word << ": " << err;
  expect_no_output();
  auto [code1, err1] = run(in + " --cracks 2 --crack-orientations one --no-elastic" + outputs());
  EXPECT_EQ(code1, 2) << err1;
  EXPECT_NE(err1.find("x not periodic"), std::string::npos) << err1;
  expect_no_output();
}

// Three orientations on a slab (12 x 3 x 18 diameters): the cracks loaded along x and y are
// samples of other sizes (W = 3 d along x): the run goes on, with a warning naming the option
// that keeps every crack along z.
TEST_F(FractureCli, ThreeOrientationsOnASlabWarn) {
  const std::string in = network(mechanics::test::slab(12, 3, 18, 11));
  auto [code, err] = run(in + " --a-over-w 0.2 --cracks 2 --no-elastic --json " + path("out.json"));
  ASSERT_EQ(code, 0) << err;
  EXPECT_NE(err.find("--crack-orientations one keeps every crack along z"), std::string::npos) << err;
  auto [code1, err1] = run(in + " --a-over-w 0.2 --cracks 2 --crack-orientations one --no-elastic --json " + path("out.json"));
  ASSERT_EQ(code1, 0) << err1;
  EXPECT_EQ(err1.find("--crack-orientations one keeps"), std::string::npos) << err1;
}
