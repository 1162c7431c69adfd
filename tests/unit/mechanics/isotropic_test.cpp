// Voigt, Reuss and Hill averages of an elastic tensor against hand formulas (Hill 1952), and their
// invariance under rotation. Tolerances 1e-12 relative: a 6×6 inverse of a well-conditioned C
// loses a few ulps (condition numbers below 10 here), far from 1e-12.
#include <gtest/gtest.h>

#include <cmath>

#include "tomodem/mechanics/isotropic.hpp"

using namespace tomodem::mechanics;

namespace {
Matrix6 cubic(double C11, double C12, double C44) {
  Matrix6 C{};
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) C[a][b] = a == b ? C11 : C12;
    C[a + 3][a + 3] = C44;
  }
  return C;
}
Matrix6 isotropic(double E, double nu) {
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  return cubic(lambda + 2 * mu, lambda, mu);
}
// Voigt index of the pair (i, j): xx, yy, zz, yz, xz, xy.
int voigt(int i, int j) { return i == j ? i : 6 - i - j; }
// C'_ijkl = Q_ip Q_jq Q_kr Q_ls C_pqrs. With engineering shear strains C_IJ = c_ijkl, no factors.
Matrix6 rotate(const Matrix6& C, const double Q[3][3]) {
  Matrix6 R{};
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = k; l < 3; ++l) {
          double s = 0;
          for (int p = 0; p < 3; ++p)
            for (int q = 0; q < 3; ++q)
              for (int r = 0; r < 3; ++r)
                for (int t = 0; t < 3; ++t) s += Q[i][p] * Q[j][q] * Q[k][r] * Q[l][t] * C[voigt(p, q)][voigt(r, t)];
          R[voigt(i, j)][voigt(k, l)] = s;
        }
  return R;
}
void expect_rel(double got, double want, const char* what) { EXPECT_NEAR(got / want, 1.0, 1e-12) << what; }
}  // namespace

TEST(IsotropicAverages, IsotropicTensorGivesItsOwnModuli) {
  for (double nu : {-0.3, 0.0, 0.17, 0.45}) {
    const IsotropicAverages a = isotropic_averages(isotropic(2e11, nu));
    expect_rel(a.E_hill, 2e11, "E_hill");
    expect_rel(a.E_voigt, 2e11, "E_voigt");
    expect_rel(a.E_reuss, 2e11, "E_reuss");
    EXPECT_NEAR(a.nu_hill, nu, 1e-12);
    EXPECT_NEAR(a.universal_anisotropy, 0.0, 1e-12);
    const AxisAverages ax = axis_averages(isotropic(2e11, nu));
    expect_rel(ax.E, 2e11, "axes E");
    EXPECT_NEAR(ax.nu, nu, 1e-12);
    EXPECT_NEAR(ax.E_spread, 0.0, 1e-12);
  }
}

// Hill (1952): for cubic symmetry K_V = K_R = (C11 + 2C12)/3, G_V = (C11 − C12 + 3C44)/5,
// G_R = 5/(4/(C11 − C12) + 3/C44). Copper-like constants (GPa), strongly anisotropic (A_Zener 3.2).
TEST(IsotropicAverages, CubicTensorMatchesHill1952) {
  const double C11 = 168e9, C12 = 121e9, C44 = 75e9;
  const double K = (C11 + 2 * C12) / 3, GV = (C11 - C12 + 3 * C44) / 5, GR = 5 / (4 / (C11 - C12) + 3 / C44);
  const IsotropicAverages a = isotropic_averages(cubic(C11, C12, C44));
  expect_rel(a.K_voigt, K, "K_V");
  expect_rel(a.K_reuss, K, "K_R");
  expect_rel(a.G_voigt, GV, "G_V");
  expect_rel(a.G_reuss, GR, "G_R");
  const double GH = (GV + GR) / 2;
  expect_rel(a.E_hill, 9 * K * GH / (3 * K + GH), "E_hill");
  expect_rel(a.nu_hill, (3 * K - 2 * GH) / (2 * (3 * K + GH)), "nu_hill");
  expect_rel(a.universal_anisotropy, 5 * GV / GR - 5, "A_U");
  EXPECT_LT(a.E_reuss, a.E_hill);
  EXPECT_LT(a.E_hill, a.E_voigt);
  // Along a cube axis: S11 = (C11 + C12)/((C11 − C12)(C11 + 2C12)), ν = C12/(C11 + C12).
  const AxisAverages ax = axis_averages(cubic(C11, C12, C44));
  expect_rel(ax.E, (C11 - C12) * (C11 + 2 * C12) / (C11 + C12), "axes E");
  expect_rel(ax.nu, C12 / (C11 + C12), "axes nu");
}

TEST(IsotropicAverages, RotatedCubicTensorGivesTheSameAverages) {
  const Matrix6 C = cubic(168e9, 121e9, 75e9);
  // Rotation by Euler angles (z, x, z) = (0.3, 0.7, 1.1) rad.
  const double a = 0.3, b = 0.7, g = 1.1;
  const double Rz1[3][3] = {{std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1}};
  const double Rx[3][3] = {{1, 0, 0}, {0, std::cos(b), -std::sin(b)}, {0, std::sin(b), std::cos(b)}};
  const double Rz2[3][3] = {{std::cos(g), -std::sin(g), 0}, {std::sin(g), std::cos(g), 0}, {0, 0, 1}};
  double T[3][3] = {}, Q[3][3] = {};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) T[i][j] += Rx[i][k] * Rz1[k][j];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) Q[i][j] += Rz2[i][k] * T[k][j];
  const Matrix6 R = rotate(C, Q);
  EXPECT_GT(std::abs(R[0][0] - C[0][0]), 1e9);  // really rotated: C11 changes
  const IsotropicAverages x = isotropic_averages(C), y = isotropic_averages(R);
  expect_rel(y.K_voigt, x.K_voigt, "K_V");
  expect_rel(y.G_voigt, x.G_voigt, "G_V");
  expect_rel(y.K_reuss, x.K_reuss, "K_R");
  expect_rel(y.G_reuss, x.G_reuss, "G_R");
  expect_rel(y.E_hill, x.E_hill, "E_hill");
  expect_rel(y.nu_hill, x.nu_hill, "nu_hill");
  expect_rel(y.universal_anisotropy, x.universal_anisotropy, "A_U");
  // The axis average is not an invariant: the rotated axes see other moduli.
  EXPECT_GT(std::abs(axis_averages(R).E / axis_averages(C).E - 1), 1e-3);
}

// An orthotropic tensor with a diagonal normal block: E_a = C_aa, ν = 0; the spread (max − min)/mean.
TEST(IsotropicAverages, AxisAverageOfAnOrthotropicTensor) {
  Matrix6 C{};
  const double d[6] = {40e9, 50e9, 60e9, 10e9, 11e9, 12e9};
  for (int a = 0; a < 6; ++a) C[a][a] = d[a];
  const AxisAverages ax = axis_averages(C);
  expect_rel(ax.E, 50e9, "E");
  EXPECT_NEAR(ax.nu, 0.0, 1e-15);
  expect_rel(ax.E_spread, 20.0 / 50, "spread");
}
