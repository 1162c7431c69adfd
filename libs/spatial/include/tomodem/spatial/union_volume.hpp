#pragma once
// Exact volume of a union of spheres (docs/physics.md#packing): each sphere clipped to its power
// (Laguerre) cell, the union being the disjoint sum of sphere ∩ cell. Only overlapping neighbours
// cut a sphere (a point of B_i with a lower power for j lies inside B_j), so each clipped volume
// is local: the sphere ∩ the half-spaces of its radical planes, computed in closed form (cone
// decomposition of the clipped polyhedron from the sphere's centre, each face integrated in
// polar coordinates about the foot of the perpendicular). Triple and higher overlaps are exact,
// unlike the pairwise sum Σ V − Σ lens.
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"

namespace tomodem::spatial {

/// A half-space {x : n·(x − c) ≤ h} relative to a sphere's centre c; n a unit vector.
struct HalfSpace {
  Vec3 n;
  double h;
};

/// The clipped sphere: its volume and the area of its spherical surface left inside.
struct ClippedSphere {
  double volume = 0;
  double sphere_area = 0;
};
/// A sphere of radius r (centre at the origin) ∩ every half-space; exact up to round-off.
ClippedSphere clip_sphere(double r, const std::vector<HalfSpace>& cuts);

/// The radical plane of spheres i and j seen from i: d = x_j − x_i (|d| > 0), keep
/// n·(x − x_i) ≤ (|d|² + r_i² − r_j²)/(2|d|), n = d/|d|.
HalfSpace radical_plane(const Vec3& d, double ri, double rj);

struct UnionVolume {
  double union_volume = 0;   ///< m³, exact
  double pairwise = 0;       ///< Σ 4/3 π r³ − Σ_pairs lens (the former estimate; ≤ union_volume)
  double spheres = 0;        ///< Σ 4/3 π r³
  std::vector<double> share; ///< per sphere: its part of the union (sphere ∩ power cell)
  std::vector<double> exposed_area;  ///< per sphere: its surface on the union's boundary
};
/// Union of the spheres in the cell (periodic images −1..1 along periodic directions).
UnionVolume union_volume(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                         int threads = 1);
/// union_volume / cell volume.
double union_relative_density(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                              int threads = 1);

}  // namespace tomodem::spatial
