// tomodem-fracture from the command line: outputs and summary keys, K_IC from the peak with the
// geometry factor of docs/physics.md#fracture-toughness, and bad input (exit 2, no output at all).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

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

TEST_F(FractureCli, CrackLongerThanSampleExits2WithoutOutput) {
  const std::string in = network(mechanics::test::slab(12, 3, 18, 11));
  auto [c1, e1] = run(in + " --geometry edge --a-over-w 1.2" + outputs());
  EXPECT_EQ(c1, 2) << e1;
  EXPECT_NE(e1.find("longer than the sample"), std::string::npos) << e1;
  auto [c2, e2] = run(in + " --geometry centre --a-over-w 0.5" + outputs());
  EXPECT_EQ(c2, 2) << e2;
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
