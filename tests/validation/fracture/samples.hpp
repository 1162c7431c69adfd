#pragma once
// Bonded random networks for the fracture tests: a periodic box (nx × ny × nz particle diameters)
// filled by random sequential insertion and densified homothetically to `density` (default 0.66,
// a partially sintered ceramic) with necks from the overlaps (tomodem-bond's density rule). Thin along y: the crack front is periodic, so
// a few diameters give plane strain at a fraction of the cost.
#include <cmath>

#include "tomodem/core/packing.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/mechanics/bonding.hpp"
#include "tomodem/mechanics/fracture.hpp"
#include "../mechanics/networks.hpp"

namespace tomodem::mechanics::test {

inline Material alumina(double E = 100e9, double nu = 0.25, double rho = 3000, double gamma = 1.0) {
  Material m = ceramic(E, nu, rho);
  m.name = "alumina";
  m.surface_energy = gamma;
  return m;
}

inline Network slab(double nx, double ny, double nz, unsigned seed, Material m = alumina(), double R = 1e-6,
                    double rsa_density = 0.36, double density = 0.66) {
  const double d = 2 * R;
  const Vec3 hi{nx * d, ny * d, nz * d};
  const int count = int(std::lround(rsa_density * hi.x * hi.y * hi.z / (4.0 / 3.0 * M_PI * R * R * R)));
  Network net;
  Packing& p = net.packing;
  for (const Vec3& x : dem::random_sites(count, R, {0, 0, 0}, hi, true, seed)) {
    p.particles.position.push_back(x);
    p.particles.radius.push_back(R);
    p.particles.phase.push_back(0);
  }
  p.cell = Cell::box({0, 0, 0}, hi, true);
  p.materials = {m};
  BondingOptions o;
  o.rule = NeckRule::density;
  o.target_density = density;
  o.min_neck_ratio = 0.05;
  bond_network(net, o);
  return net;
}

/// Laws with the LEFM criterion from the materials (Γ = γ_i + γ_j).
/// `isolated_necks`: every neck as if alone (no Laguerre-face cap), for hand-made bond sets whose
/// bonded pairs need not be tessellation neighbours.
inline std::vector<dem::BondLaw> lefm_laws(const Packing& p, FailureOptions& f, bool isolated_necks = false) {
  f.criterion = dem::BondFailure::lefm;
  LawOptions o;
  o.face_cap = !isolated_necks;
  std::vector<dem::BondLaw> laws = bond_laws(p, "", o, true);
  set_failure(laws, p, f, "");
  return laws;
}

}  // namespace tomodem::mechanics::test
