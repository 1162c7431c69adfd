// Hashin–Shtrikman upper bounds of a porous solid: the two-phase bounds with the void's moduli
// set to zero (docs/physics.md#bounds has the derivation).
#include "tomodem/mechanics/bounds.hpp"

#include <algorithm>
#include <vector>

#include "tomodem/spatial/union_volume.hpp"

namespace tomodem::mechanics {

namespace {
/// HS upper bounds with a void phase for a solid of moduli K, G (any unit); E from K and G.
PorousBounds hs_void(double phi, double K, double G) {
  phi = std::clamp(phi, 0.0, 1.0);
  const double f = 1 - phi;
  PorousBounds b;
  const double k = 4 * G * K * phi / (4 * G + 3 * K * f);
  const double g = G * phi * (9 * K + 8 * G) / (9 * K + 8 * G + 6 * (K + 2 * G) * f);
  b.K_over_Ks = k / K;
  b.G_over_Gs = g / G;
  b.E_over_Es = (3 * k + g > 0 ? 9 * k * g / (3 * k + g) : 0) / (9 * K * G / (3 * K + G));
  b.voigt_E_over_Es = phi;
  return b;
}
}  // namespace

PorousBounds porous_upper_bounds(double phi, double nu_s) {
  // In units of E_s: K_s = 1/(3(1 − 2ν)), G_s = 1/(2(1 + ν)).
  return hs_void(phi, 1 / (3 * (1 - 2 * nu_s)), 1 / (2 * (1 + nu_s)));
}

StiffnessBoundCheck check_stiffness_bound(const Packing& p, double E) {
  StiffnessBoundCheck c;
  c.relative_density = spatial::union_relative_density(p.particles.position, p.particles.radius, p.cell);
  std::vector<char> present(p.materials.size(), 0);
  for (int ph : p.particles.phase)
    if (ph >= 0 && std::size_t(ph) < present.size()) present[std::size_t(ph)] = 1;
  for (std::size_t k = 0; k < present.size(); ++k)
    if (present[k]) c.E_s = std::max(c.E_s, p.materials[k].youngs_modulus);
  if (!(c.E_s > 0)) return c;
  // Several phases: the HS upper bound rises with each phase's K and G, so a solid of the largest
  // K and the largest G present bounds them all (one phase: the bound itself).
  double K = 0, G = 0;
  for (std::size_t k = 0; k < present.size(); ++k)
    if (present[k]) {
      const Material& m = p.materials[k];
      K = std::max(K, m.youngs_modulus / (3 * (1 - 2 * m.poisson_ratio)));
      G = std::max(G, m.youngs_modulus / (2 * (1 + m.poisson_ratio)));
    }
  c.hs_upper_E_over_Es = hs_void(c.relative_density, K, G).E_over_Es * (9 * K * G / (3 * K + G)) / c.E_s;
  c.voigt_E_over_Es = std::clamp(c.relative_density, 0.0, 1.0);
  c.E_over_Es = E / c.E_s;
  c.exceeded = c.E_over_Es > c.hs_upper_E_over_Es;
  return c;
}

}  // namespace tomodem::mechanics
