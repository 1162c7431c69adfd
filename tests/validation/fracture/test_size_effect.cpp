// The size-effect fits (docs/fracture.md#size-effect) on data made from the laws themselves, and
// the crop of geometrically similar windows from one network.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "samples.hpp"
#include "tomodem/mechanics/fracture.hpp"
#include "tomodem/mechanics/size_effect.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

TEST(SizeEffect, BazantFitRecoversItsOwnLaw) {
  // K = K∞ / sqrt(1 + W0/W) with K∞ = 1.5e5, W0 = 30 µm at W = 20, 40, 80 µm: exact points.
  const double Kinf = 1.5e5, W0 = 30e-6;
  std::vector<double> W = {20e-6, 40e-6, 80e-6}, K, e(3, 0.05);
  for (double w : W) K.push_back(Kinf / std::sqrt(1 + W0 / w));
  const SizeEffectFit f = fit_size_effect(W, K, e, SizeEffectLaw::bazant);
  EXPECT_NEAR(f.K_inf / Kinf, 1.0, 1e-12);
  EXPECT_NEAR(f.length / W0, 1.0, 1e-9);
  EXPECT_NEAR(f.chi2, 0.0, 1e-12);
  EXPECT_EQ(f.dof, 1);
  // Standard error from the weights alone (χ² = 0 < dof): α = 1/K∞², σ_y = 2 σ_K/K³ per point.
  // By hand: the intercept variance of a weighted line is Σw x² / (Σw Σw x² − (Σw x)²).
  double S = 0, Sx = 0, Sxx = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const double sy = 2 * 0.05 * K[i] / std::pow(K[i], 3), w = 1 / (sy * sy), x = 1 / W[i];
    S += w, Sx += w * x, Sxx += w * x * x;
  }
  const double va = Sxx / (S * Sxx - Sx * Sx);
  EXPECT_NEAR(f.K_inf_error / (0.5 * std::pow(Kinf, 3) * std::sqrt(va)), 1.0, 1e-9);
}

TEST(SizeEffect, LinearFitAndScatterScaledError) {
  // K = K∞ (1 − c/W), K∞ = 1e5, c = 5 µm; then one point moved by 3 σ: the Birge ratio scales the error up.
  const double Kinf = 1e5, c = 5e-6;
  std::vector<double> W = {20e-6, 40e-6, 80e-6}, K, e(3, 0.01);
  for (double w : W) K.push_back(Kinf * (1 - c / w));
  SizeEffectFit f = fit_size_effect(W, K, e, SizeEffectLaw::linear);
  EXPECT_NEAR(f.K_inf / Kinf, 1.0, 1e-12);
  EXPECT_NEAR(f.length / c, 1.0, 1e-9);
  const double clean = f.K_inf_error;
  K[1] *= 1.03;
  f = fit_size_effect(W, K, e, SizeEffectLaw::linear);
  EXPECT_GT(f.chi2, 1.0);
  // dof = 1: the error grows by sqrt(χ²); 2% because the moved point's own σ (1% of K) moved by 3% too.
  EXPECT_NEAR(f.K_inf_error / clean / std::sqrt(f.chi2), 1.0, 0.02);
  // Fewer than three widths: no fit.
  EXPECT_TRUE(std::isnan(fit_size_effect({1e-5, 2e-5}, {1e5, 1.1e5}, {0.1, 0.1}, SizeEffectLaw::linear).K_inf));
}

TEST(SizeEffect, CropKeepsTheWindowAndItsInnerBonds) {
  const Network net = mechanics::test::slab(24, 3, 24, 7);
  const double L = net.packing.cell.h(0, 0);
  const Network half = crop_network(net, 0.5 * L, 0.5 * net.packing.cell.h(2, 2));
  const std::size_t n = half.packing.particles.size();
  // A uniform random packing: the window holds about a quarter of the particles (±10%, ~500 of 2 000).
  EXPECT_NEAR(double(n) / double(net.packing.particles.size()), 0.25, 0.025);
  for (const Vec3& x : half.packing.particles.position) {
    EXPECT_GE(x.x, half.packing.cell.origin.x);
    EXPECT_LT(x.x, half.packing.cell.origin.x + 0.5 * L);
  }
  for (std::size_t b = 0; b < half.packing.bonds.size(); ++b) {
    EXPECT_EQ(half.image[b][0], 0);
    EXPECT_EQ(half.image[b][2], 0);
    EXPECT_LT(norm(bond_vector(half.packing, half.image[b], b)), 4 * half.packing.particles.radius[0]);
  }
  CrackOptions c;
  c.a_over_w = 0.1875;
  const FractureSample s = make_sample(half, c);
  EXPECT_NEAR(s.W, 0.5 * L, 1e-12 * L);
  EXPECT_GT(s.ligament_bonds, 0);
}

// --widths' summary (size_effect_fits_json): when K_IC grows faster than sqrt(W) the intercept of
// 1/K² against 1/W is negative and Bažant's law has no finite K∞: the summary says why and gives
// the first-order law's K∞ (the estimate docs/rve.md quotes) as the large-sample value.
// K = K1 (W/W1)^0.75: 1/K² ∝ x^1.5 (x = 1/W) is convex and 0 at x = 0, so every line through its
// points has a negative intercept (by hand, x ∝ 1, 0.5, 0.25: unweighted fit −0.20, the secant of
// the two widest −0.10, in units of the first point's y).
TEST(SizeEffect, NoFiniteBazantLimitFallsBackToTheFirstOrderLaw) {
  std::vector<double> W = {20e-6, 40e-6, 80e-6}, K, e(3, 0.05);
  for (double w : W) K.push_back(1e5 * std::pow(w / 20e-6, 0.75));
  const nlohmann::json j = nlohmann::json::parse(size_effect_fits_json(W, K, e));
  EXPECT_TRUE(j["bazant"]["K_inf"].is_null());
  ASSERT_TRUE(j["bazant"].contains("reason"));
  EXPECT_NE(j["bazant"]["reason"].get<std::string>().find("not positive"), std::string::npos);
  EXPECT_EQ(j["K_inf_law"], "linear");
  const SizeEffectFit lin = fit_size_effect(W, K, e, SizeEffectLaw::linear);
  EXPECT_EQ(j["K_inf"].get<double>(), lin.K_inf);
  EXPECT_EQ(j["K_inf_error"].get<double>(), lin.K_inf_error);
  // Bažant's own law (K∞ = 1.5e5, W0 = 30 µm): finite, so it is the large-sample value, no reason.
  K.clear();
  for (double w : W) K.push_back(1.5e5 / std::sqrt(1 + 30e-6 / w));
  const nlohmann::json b = nlohmann::json::parse(size_effect_fits_json(W, K, e));
  EXPECT_EQ(b["K_inf_law"], "bazant");
  EXPECT_NEAR(b["K_inf"].get<double>() / 1.5e5, 1.0, 1e-12);
  EXPECT_FALSE(b["bazant"].contains("reason"));
}
