// Voigt, Reuss and Hill averages of an elastic tensor (docs/young.md#isotropic-estimate).
#include "tomodem/mechanics/isotropic.hpp"

#include <Eigen/Dense>
#include <algorithm>

namespace tomodem::mechanics {

double youngs_from_bulk_shear(double K, double G) { return 9 * K * G / (3 * K + G); }
double poisson_from_bulk_shear(double K, double G) { return (3 * K - 2 * G) / (2 * (3 * K + G)); }

namespace {
// The three sums the Voigt and Reuss formulas use: normal diagonal, normal off-diagonal, shear diagonal.
struct VoigtSums {
  double diag = 0, off = 0, shear = 0;
};
template <class M>
VoigtSums sums(const M& m) {
  VoigtSums s;
  for (int a = 0; a < 3; ++a) {
    s.diag += m(a, a);
    s.off += m(a, (a + 1) % 3);
    s.shear += m(a + 3, a + 3);
  }
  return s;
}
}  // namespace

IsotropicAverages isotropic_averages(const Matrix6& C) {
  Eigen::Matrix<double, 6, 6> c;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) c(a, b) = C[a][b];
  c = 0.5 * (c + c.transpose());  // C is symmetric up to the solver's residual
  const Eigen::Matrix<double, 6, 6> s = c.inverse();
  const VoigtSums v = sums(c), r = sums(s);
  IsotropicAverages out;
  out.K_voigt = (v.diag + 2 * v.off) / 9;
  out.G_voigt = (v.diag - v.off + 3 * v.shear) / 15;
  out.K_reuss = 1 / (r.diag + 2 * r.off);
  out.G_reuss = 15 / (4 * r.diag - 4 * r.off + 3 * r.shear);
  out.K_hill = 0.5 * (out.K_voigt + out.K_reuss);
  out.G_hill = 0.5 * (out.G_voigt + out.G_reuss);
  out.E_voigt = youngs_from_bulk_shear(out.K_voigt, out.G_voigt);
  out.E_reuss = youngs_from_bulk_shear(out.K_reuss, out.G_reuss);
  out.E_hill = youngs_from_bulk_shear(out.K_hill, out.G_hill);
  out.nu_hill = poisson_from_bulk_shear(out.K_hill, out.G_hill);
  out.universal_anisotropy = 5 * out.G_voigt / out.G_reuss + out.K_voigt / out.K_reuss - 6;
  return out;
}

AxisAverages axis_averages(const Matrix6& C) {
  AxisAverages out;
  double lo = 0, hi = 0;
  for (int a = 0; a < 3; ++a) {
    double E = 0, nu = 0;
    uniaxial_from_tensor(C, a, E, nu);  // nu: the mean of ν_ab over the two lateral axes b
    out.E += E / 3;
    out.nu += nu / 3;
    lo = a == 0 ? E : std::min(lo, E);
    hi = a == 0 ? E : std::max(hi, E);
  }
  out.E_spread = (hi - lo) / out.E;
  return out;
}

}  // namespace tomodem::mechanics
