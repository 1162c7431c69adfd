// Hashin–Shtrikman upper bounds of a porous solid (mechanics/bounds.hpp) against values computed
// by hand from the two-phase bounds with a void phase, and their limits.
#include <gtest/gtest.h>

#include "tomodem/mechanics/bounds.hpp"

using tomodem::mechanics::porous_upper_bounds;

TEST(PorousBounds, HandComputedValues) {
  // φ = 0.75, ν_s = 0.3 (E_s = 1): K_s = 1/1.2 = 0.833333, G_s = 1/2.6 = 0.384615;
  // K = 4·0.384615·0.833333·0.75/(1.538462 + 3·0.833333·0.25) = 0.961538/2.163462 = 0.444444;
  // G = 0.384615·0.75·10.576923/(10.576923 + 6·1.602564·0.25) = 3.051036/12.980769 = 0.235043,
  //   G/G_s = 0.611111 (the two-phase form G_s + f_2/(−1/G_s + 6φ(K_s + 2G_s)/(5G_s(3K_s + 4G_s))) gives the same);
  // E = 9KG/(3K + G) = 0.940176/1.568376 = 0.599455 (the 0.599). Six digits by hand.
  const auto b = porous_upper_bounds(0.75, 0.3);
  EXPECT_NEAR(b.K_over_Ks, 0.444444 / 0.833333, 2e-6);
  EXPECT_NEAR(b.G_over_Gs, 0.611111, 2e-6);
  EXPECT_NEAR(b.E_over_Es, 0.599455, 2e-6);
  EXPECT_EQ(b.voigt_E_over_Es, 0.75);
  // φ = 0.78, ν_s = 0.22 (the sintered network, bound 0.64): K_s = 0.595238, G_s = 0.409836;
  // K = 4·0.409836·0.595238·0.78/(1.639344 + 3·0.595238·0.22) = 0.761124/2.032201 = 0.374532;
  // G = 0.409836·0.78·(5.357143 + 3.278689)/(8.635832 + 6·1.414910·0.22) = 2.760635/10.503513 = 0.262830;
  // E = 9·0.374532·0.262830/(1.123596 + 0.262830) = 0.885942/1.386426 = 0.639012.
  EXPECT_NEAR(porous_upper_bounds(0.78, 0.22).E_over_Es, 0.639012, 3e-6);
}

TEST(PorousBounds, Limits) {
  for (double nu : {-0.5, 0.0, 0.22, 0.3, 0.45}) {
    EXPECT_NEAR(porous_upper_bounds(1.0, nu).E_over_Es, 1.0, 1e-14) << nu;  // the dense solid
    EXPECT_EQ(porous_upper_bounds(0.0, nu).E_over_Es, 0.0) << nu;           // all void
    // φ → 0: K ≈ 4G_sK_sφ/(4G_s + 3K_s), G ≈ G_sφ(9K_s + 8G_s)/(15K_s + 20G_s): E linear in φ.
    const double K = 1 / (3 * (1 - 2 * nu)), G = 1 / (2 * (1 + nu)), phi = 1e-7;
    const double k = 4 * G * K * phi / (4 * G + 3 * K), g = G * phi * (9 * K + 8 * G) / (15 * K + 20 * G);
    EXPECT_NEAR(porous_upper_bounds(phi, nu).E_over_Es, 9 * k * g / (3 * k + g), 1e-6 * phi) << nu;
    // Below Voigt (φ) everywhere, and increasing in φ.
    double prev = 0;
    for (double f = 0.05; f < 1; f += 0.05) {
      const auto b = porous_upper_bounds(f, nu);
      EXPECT_LT(b.E_over_Es, b.voigt_E_over_Es) << nu << " " << f;
      EXPECT_GT(b.E_over_Es, prev);
      prev = b.E_over_Es;
    }
  }
}
