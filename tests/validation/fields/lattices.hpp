#pragma once
// Packings with closed-form stresses for the coarse-graining tests: simple cubic lattices with
// linear springs between nearest neighbours, in a periodic cell, under a homogeneous affine strain.
#include <cmath>
#include <random>

#include "tomodem/core/packing.hpp"

namespace tomodem::fields::test {

/// n³ simple cubic lattice, spacing a, radius a/2, one material of density rho, periodic cell.
/// `F` maps the unstrained lattice (and cell) affinely. Contacts to the +x, +y, +z neighbour of
/// every particle carry the linear spring force k (a - |d|) along d (on j from i).
inline Packing spring_lattice(int n, double a, const Mat3& F, double k, double rho = 2500) {
  Packing p;
  p.cell.h = F * Mat3::diagonal({n * a, n * a, n * a});
  p.cell.periodic[0] = p.cell.periodic[1] = p.cell.periodic[2] = true;
  auto id = [n](int i, int j, int l) { return ((i % n) * n + (j % n)) * n + (l % n); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int l = 0; l < n; ++l) {
        p.particles.position.push_back(F * Vec3((i + 0.5) * a, (j + 0.5) * a, (l + 0.5) * a));
        p.particles.radius.push_back(0.5 * a);
        p.particles.phase.push_back(0);
      }
  Material m;
  m.name = "grain";
  m.youngs_modulus = 1e9;
  m.poisson_ratio = 0.25;
  m.density = rho;
  p.materials.push_back(m);
  const Vec3 e[3] = {{a, 0, 0}, {0, a, 0}, {0, 0, a}};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int l = 0; l < n; ++l)
        for (int c = 0; c < 3; ++c) {
          const Vec3 d = F * e[c];
          const double len = norm(d);
          p.contacts.i.push_back(id(i, j, l));
          p.contacts.j.push_back(id(i + (c == 0), j + (c == 1), l + (c == 2)));
          p.contacts.overlap.push_back(a - len);
          p.contacts.normal_force.push_back((k * (a - len) / len) * d);
          p.contacts.tangential_force.push_back({0, 0, 0});
        }
  return p;
}

/// Largest |A - B| over the 9 components, relative to |B| (Frobenius).
inline double relative_difference(const double* A, const Mat3& B) {
  double nb = 0, worst = 0;
  for (int c = 0; c < 9; ++c) nb += B.a[c / 3][c % 3] * B.a[c / 3][c % 3];
  for (int c = 0; c < 9; ++c) worst = std::max(worst, std::abs(A[c] - B.a[c / 3][c % 3]));
  return worst / std::sqrt(nb);
}

}  // namespace tomodem::fields::test
