// From the shared data model to what the coarse-graining sums: masses, forces, branch vectors.
#include <cmath>

#include "tomodem/core/error.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/fields/block.hpp"
#include "tomodem/fields/tool.hpp"

namespace tomodem::fields {

using spatial::shortest_branch;

namespace {
constexpr double kPi = 3.14159265358979323846;

}  // namespace

std::vector<double> particle_masses(const Packing& p, const std::string& file, double density) {
  const auto& P = p.particles;
  std::vector<double> m(P.size());
  for (std::size_t i = 0; i < P.size(); ++i) {
    double rho = density;
    if (rho <= 0) {
      if (p.materials.empty())
        throw InputError(file, "/materials", "absent", "the masses need material densities: give --density (kg/m^3)");
      const int k = P.phase[i];
      rho = p.materials[k].density;
      if (!(rho > 0) || !std::isfinite(rho))
        throw InputError(file, "/materials/" + std::to_string(k) + "/@density_kg_per_m3", value_text(rho),
                         "the density must be finite and > 0 (or give --density)");
    }
    m[i] = rho * 4.0 / 3.0 * kPi * P.radius[i] * P.radius[i] * P.radius[i];
  }
  return m;
}

namespace {

/// Normal bond force from the stretch, F_n = -k_n (|d| - L0) on j (docs/physics.md#bond-forces),
/// with the bond stiffness of the DEM loop at its default large-neck coefficients.
Vec3 stretch_force(const Packing& p, const std::string& file, std::size_t b, const Vec3& d) {
  const auto& B = p.bonds;
  const int pi = p.particles.phase[B.i[b]], pj = p.particles.phase[B.j[b]];
  double inv = 0;
  for (int k : {pi, pj}) {
    const Material& m = p.materials[k];
    if (!(m.youngs_modulus > 0) || !(m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
      throw InputError(file, "/materials/" + std::to_string(k), value_text(m.youngs_modulus),
                       "bond forces from the stretch need E > 0 and -1 < nu < 0.5 (or --bond-forces none)");
    inv += (1 - m.poisson_ratio * m.poisson_ratio) / m.youngs_modulus;
  }
  dem::BondLaw law;
  law.E_star = 1 / inv;
  const double kn = dem::bond_stiffness(law, B.radius[b], p.particles.radius[B.i[b]], p.particles.radius[B.j[b]]).kn;
  const double len = norm(d);
  return (-kn * (len - B.rest_length[b]) / len) * d;
}

std::vector<PairForce> bond_pairs(const Packing& p, const std::string& file, const SnapshotOptions& o,
                                  std::string* source) {
  const auto& B = p.bonds;
  std::string mode = o.bond_forces;
  if (mode == "auto")
    mode = B.size() == 0 ? "none" : !o.stored_bond_force.empty() ? "stored" : !p.materials.empty() ? "stretch" : "none";
  if (mode == "stored" && o.stored_bond_force.size() != B.size())
    throw InputError(file, "/bonds/force", std::to_string(o.stored_bond_force.size()) + " rows",
                     "--bond-forces stored needs one force per bond (" + std::to_string(B.size()) + ")");
  if (mode == "stretch" && p.materials.empty() && B.size())
    throw InputError(file, "/materials", "absent", "--bond-forces stretch needs E and nu of the materials");
  if (source) *source = mode;
  std::vector<PairForce> out;
  if (mode == "none") return out;
  for (std::size_t b = 0; b < B.size(); ++b) {
    if (B.state[b] != BondTable::intact) continue;
    PairForce c;
    c.i = B.i[b], c.j = B.j[b];
    const Vec3 &xi = p.particles.position[c.i], &xj = p.particles.position[c.j];
    if (!o.bond_image.empty()) {
      const auto& n = o.bond_image[b];
      c.branch = xj + p.cell.h * spatial::as_vector(n) - xi;
    } else {
      c.branch = shortest_branch(p.cell, xi, xj);
    }
    c.force = mode == "stored" ? o.stored_bond_force[b] : stretch_force(p, file, b, c.branch);
    out.push_back(c);
  }
  return out;
}

/// u = x + H·n - x_ref with the image n nearest the affine map of x_ref onto the current cell;
/// x becomes that image, so that each particle carries the displacement of where it sits.
std::vector<Vec3> displacements(const Packing& p, const Packing& ref, const std::string& ref_file,
                                std::vector<Vec3>& x) {
  const std::size_t N = p.particles.size();
  if (ref.particles.size() != N)
    throw InputError(ref_file, "/particles/radius", std::to_string(ref.particles.size()) + " particles",
                     "the reference must hold the same particles, in the same order (" + std::to_string(N) + ")");
  const Mat3 F = p.cell.h * ref.cell.h.inverse();
  std::vector<Vec3> u(N);
  for (std::size_t i = 0; i < N; ++i) {
    const Vec3 xr = ref.particles.position[i];
    const Vec3 affine = p.cell.origin + F * (xr - ref.cell.origin);
    x[i] = affine + shortest_branch(p.cell, affine, p.particles.position[i]);
    u[i] = x[i] - xr;
  }
  return u;
}
}  // namespace

Snapshot make_snapshot(const Packing& p, const std::string& file, const SnapshotOptions& o, const Packing* reference,
                       const std::string& reference_file, std::string* bond_source) {
  Snapshot s;
  s.cell = p.cell;
  s.x = p.particles.position;
  s.v = p.particles.velocity;
  s.m = particle_masses(p, file, o.density);
  const auto& C = p.contacts;
  s.contacts.reserve(C.size());
  for (std::size_t c = 0; c < C.size(); ++c) {
    PairForce f;
    f.i = C.i[c], f.j = C.j[c];
    f.branch = shortest_branch(p.cell, s.x[f.i], s.x[f.j]);
    f.force = C.normal_force[c] + C.tangential_force[c];
    s.contacts.push_back(f);
  }
  s.bonds = bond_pairs(p, file, o, bond_source);
  if (reference) {
    s.u = displacements(p, *reference, reference_file, s.x);
    s.h_reference = reference->cell.h;
  }
  return s;
}

}  // namespace tomodem::fields
