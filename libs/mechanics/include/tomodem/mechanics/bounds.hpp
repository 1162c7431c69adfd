#pragma once
// Upper bounds on the elastic moduli of a porous isotropic solid (docs/physics.md#bounds): the
// Hashin–Shtrikman upper bound with a void phase (Hashin & Shtrikman 1963) and Voigt's. Every
// E/E_s that young reports is checked against them at the union-volume relative density.
#include "tomodem/core/packing.hpp"

namespace tomodem::mechanics {

struct PorousBounds {
  double K_over_Ks = 0;   ///< HS upper: 4 G_s φ / (4 G_s + 3 K_s (1 − φ))
  double G_over_Gs = 0;   ///< HS upper: φ (9K_s + 8G_s) / (9K_s + 8G_s + 6 (K_s + 2G_s)(1 − φ))
  double E_over_Es = 0;   ///< E from K and G: 9KG/(3K + G), over E_s
  double voigt_E_over_Es = 0;  ///< φ
};
/// Solid fraction φ in [0, 1], solid Poisson ratio ν_s in (−1, 0.5).
PorousBounds porous_upper_bounds(double phi, double nu_s);

/// A measured modulus against the bounds at the packing's union-volume relative density.
struct StiffnessBoundCheck {
  double relative_density = 0;  ///< exact union volume / cell volume
  double E_s = 0;               ///< the stiffest solid phase present, Pa
  double E_over_Es = 0;
  double hs_upper_E_over_Es = 0;  ///< max over phases present of (E_k/E_s) × the HS bound with ν_k
  double voigt_E_over_Es = 0;     ///< φ
  bool exceeded = false;          ///< E/E_s above the HS upper bound
};
/// Needs materials with E > 0 for the phases present (as young and fracture check first).
StiffnessBoundCheck check_stiffness_bound(const Packing& p, double E);

}  // namespace tomodem::mechanics
