// tomodem-young's isotropic estimate (docs/young.md#isotropic-estimate) on a random bonded network:
// with --no-tensor, E_iso and nu_iso are the means over three single-axis runs; with the full
// tensor, Hill's E_iso lies between Reuss's and Voigt's; the bound flag covers E_iso.
#include <gtest/gtest.h>

#include <cmath>

#include "../../validation/mechanics/networks.hpp"
#include "../common/tool_test.hpp"

using namespace tomodem;

namespace {
class YoungIsotropic : public tomodem::test::ToolTest {
 protected:
  YoungIsotropic() : ToolTest("tomodem-young-iso-e2e") {}
  // 300 random spheres densified to 0.55: a few per cent anisotropic, as a sintered sample.
  std::string network() const {
    const mechanics::Network net = mechanics::test::random_network(300, 0.5e-3, 0.30, 0.55, 7, 0.05);
    mechanics::write_network(path("net.h5"), net);
    return path("net.h5");
  }
  nlohmann::json young(const std::string& in, const std::string& args, const std::string& name) const {
    const int code = sh(bin("tomodem-young") + " " + in + " --method implicit --solver ldlt -q " + args + " --json " + path(name));
    EXPECT_EQ(code, 0) << text("stderr.txt");
    return json(name);
  }
};
}  // namespace

TEST_F(YoungIsotropic, NoTensorGivesTheMeanOfTheThreeAxes) {
  const std::string in = network();
  const auto iso = young(in, "--no-tensor", "iso.json");
  EXPECT_EQ(iso["iso_method"], "axes");
  double E = 0, nu = 0, lo = 1e300, hi = 0;
  for (const char* axis : {"x", "y", "z"}) {
    const auto one = young(in, std::string("--no-tensor --axis ") + axis, std::string(axis) + ".json");
    E += one["E"].get<double>() / 3;
    nu += one["nu"].get<double>() / 3;
    lo = std::min(lo, one["E"].get<double>());
    hi = std::max(hi, one["E"].get<double>());
  }
  // 1e-9: each run solves the same matrix by LDLT; the runs agree to round-off.
  EXPECT_NEAR(iso["E_iso"].get<double>() / E, 1.0, 1e-9);
  EXPECT_NEAR(iso["nu_iso"].get<double>(), nu, 1e-9);
  EXPECT_NEAR(iso["anisotropy"]["E_axes_spread"].get<double>(), (hi - lo) / E, 1e-9);
  EXPECT_GT(hi - lo, 1e-3 * E);  // the sample is anisotropic: the test tells the axes apart
  EXPECT_TRUE(iso["anisotropy"]["A_U"].is_null());
  EXPECT_FALSE(iso.contains("E_voigt"));  // Voigt and Reuss need the six cases
  EXPECT_DOUBLE_EQ(iso["E_iso_error"].get<double>(), iso["E_error"].get<double>());
  EXPECT_NEAR(iso["E_iso_over_Es"].get<double>(), E / 1e9, 1e-9);  // ceramic(): E_s = 1 GPa
}

TEST_F(YoungIsotropic, FullTensorHillLiesBetweenReussAndVoigt) {
  const auto h = young(network(), "", "full.json");
  EXPECT_EQ(h["iso_method"], "hill");
  const double E = h["E_iso"].get<double>(), EV = h["E_voigt"].get<double>(), ER = h["E_reuss"].get<double>();
  EXPECT_LT(ER, E);
  EXPECT_LT(E, EV);
  EXPECT_NEAR(E / (0.5 * (EV + ER)), 1.0, 0.01);  // Hill's E from the mean K, G is near the mean E
  const double K = h["K_iso"].get<double>(), G = h["G_iso"].get<double>();
  EXPECT_NEAR(E / (9 * K * G / (3 * K + G)), 1.0, 1e-12);
  EXPECT_NEAR(h["nu_iso"].get<double>(), (3 * K - 2 * G) / (2 * (3 * K + G)), 1e-12);
  EXPECT_GT(h["anisotropy"]["A_U"].get<double>(), 0.0);  // A_U >= 0, 0 only when isotropic
  // The flag is E's or E_iso's excess over the HS bound.
  const double hs = h["hs_upper_E_over_Es"].get<double>();
  EXPECT_EQ(h["bound_exceeded"].get<bool>(), h["E_over_Es"].get<double>() > hs || h["E_iso_over_Es"].get<double>() > hs);
}

// A simple cubic lattice with necks a = 0.9 R: its axes carry the solid's modulus, beyond the HS bound
// at φ = π/6, and so does the isotropic average: the flag and a warning naming E_iso.
TEST_F(YoungIsotropic, BoundWarningCoversEIso) {
  mechanics::Network net;
  net.packing = mechanics::test::lattice("simple_cubic", 4, 1e-3, 0.5e-3, mechanics::test::ceramic(1e9, 0.2));
  mechanics::test::bond_ratio(net, 0.9);
  mechanics::write_network(path("sc.h5"), net);
  const int code = sh(bin("tomodem-young") + " " + path("sc.h5") + " --method implicit --json " + path("sc.json"));
  ASSERT_EQ(code, 0) << text("stderr.txt");
  const auto s = json("sc.json");
  ASSERT_GT(s["E_iso_over_Es"].get<double>(), s["hs_upper_E_over_Es"].get<double>());
  EXPECT_TRUE(s["bound_exceeded"].get<bool>());
  EXPECT_NE(text("stderr.txt").find("E_iso/E_s"), std::string::npos) << text("stderr.txt");
}
