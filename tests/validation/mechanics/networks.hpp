#pragma once
// Bonded networks for the mechanics tests: lattices and random packings on periodic cells.
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/mechanics/bonding.hpp"

namespace tomodem::mechanics::test {

inline Material ceramic(double E = 1e9, double nu = 0.25, double rho = 2500) {
  Material m;
  m.name = "ceramic";
  m.youngs_modulus = E;
  m.poisson_ratio = nu;
  m.density = rho;
  return m;
}

/// Spheres at lattice sites (simple_cubic, bcc, fcc) with n cells of constant a, periodic cube.
inline Packing lattice(const std::string& kind, int n, double a, double radius, Material m = ceramic()) {
  Packing p;
  const std::optional<dem::LatticeKind> lattice = dem::parse_lattice(kind);
  if (!lattice) throw std::invalid_argument("test::lattice: unknown lattice " + kind);
  for (const Vec3& x : dem::lattice_sites(*lattice, n, a)) {
    p.particles.position.push_back(x);
    p.particles.radius.push_back(radius);
    p.particles.phase.push_back(0);
  }
  p.cell = Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true);
  p.materials = {m};
  return p;
}

/// Bonds every touching pair (gap tolerance 1e-6 R) with the given neck ratio.
inline BondingReport bond_ratio(Network& net, double ratio) {
  BondingOptions o;
  o.rule = NeckRule::ratio;
  o.neck_ratio = ratio;
  o.gap_tolerance = 1e-6;
  return bond_network(net, o);
}

/// A random periodic packing: random sequential insertion at `rsa_density`, then homothetic
/// densification to `density` (tomodem-bond's density rule) with necks from the overlaps.
inline Network random_network(int count, double radius, double rsa_density, double density, unsigned seed,
                              double min_neck_ratio = 0.01, Material m = ceramic()) {
  const double L = std::cbrt(count * 4.0 / 3.0 * M_PI * radius * radius * radius / rsa_density);
  Network net;
  Packing& p = net.packing;
  for (const Vec3& x : dem::random_sites(count, radius, {0, 0, 0}, {L, L, L}, true, seed)) {
    p.particles.position.push_back(x);
    p.particles.radius.push_back(radius);
    p.particles.phase.push_back(0);
  }
  p.cell = Cell::box({0, 0, 0}, {L, L, L}, true);
  p.materials = {m};
  BondingOptions o;
  o.rule = NeckRule::density;
  o.target_density = density;
  o.min_neck_ratio = min_neck_ratio;
  bond_network(net, o);
  return net;
}

}  // namespace tomodem::mechanics::test
