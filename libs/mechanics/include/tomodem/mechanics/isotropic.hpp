#pragma once
// Isotropic estimates of a measured elastic tensor (docs/young.md#isotropic-estimate): the Voigt,
// Reuss and Hill averages of the 6×6 C (Hill 1952), the universal anisotropy index (Ranganathan
// & Ostoja-Starzewski 2008), and the axis average of the normal block for three strain cases.
#include "tomodem/mechanics/elastic.hpp"

namespace tomodem::mechanics {

/// E = 9KG/(3K + G), ν = (3K − 2G)/(2(3K + G)) of an isotropic solid.
double youngs_from_bulk_shear(double K, double G);
double poisson_from_bulk_shear(double K, double G);

struct IsotropicAverages {
  double K_voigt = 0, G_voigt = 0;  ///< from C: K = Σ_ij C_ij(i,j ≤ 3)/9, G = (tr − off + 3 shear)/15
  double K_reuss = 0, G_reuss = 0;  ///< from S = C⁻¹, the same sums of compliances
  double K_hill = 0, G_hill = 0;    ///< arithmetic means of Voigt and Reuss
  double E_voigt = 0, E_reuss = 0, E_hill = 0, nu_hill = 0;
  double universal_anisotropy = 0;  ///< A_U = 5 G_V/G_R + K_V/K_R − 6 (0 when isotropic)
};
/// C in Voigt order xx, yy, zz, yz, xz, xy with engineering shear strains; must be invertible.
IsotropicAverages isotropic_averages(const Matrix6& C);

/// Three normal strain cases only: E = mean of E_x, E_y, E_z (E_a = 1/S_aa of the normal block's
/// inverse), ν = mean of the six ν_ab = −S_ba/S_aa.
struct AxisAverages {
  double E = 0, nu = 0;
  double E_spread = 0;  ///< (max − min)/mean of the three E_a
};
AxisAverages axis_averages(const Matrix6& C);

}  // namespace tomodem::mechanics
