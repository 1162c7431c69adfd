#pragma once
// Overlap geometry of spheres, and the one definition of a contact used by every tool.
#include <algorithm>
#include <cmath>

namespace tomodem::spatial {

inline constexpr double kPi = 3.14159265358979323846;

inline double sphere_volume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }

/// Volume of the spherical cap of a sphere of radius r beyond a plane at signed distance d from
/// its centre (d ≥ r: 0; d ≤ −r: the whole sphere): π h² (3r − h)/3 with cap height h = r − d.
inline double cap_volume(double r, double d) {
  if (d >= r) return 0;
  if (d <= -r) return sphere_volume(r);
  const double h = r - d;
  return kPi * h * h * (3 * r - h) / 3;
}

/// Volume of the intersection (lens) of two spheres of radii r1, r2 whose centres are d apart:
/// the sum of the two caps cut by the radical plane; the smaller sphere when one is inside the
/// other, 0 when they are apart.
inline double lens_volume(double r1, double r2, double d) {
  if (d >= r1 + r2) return 0;
  if (d <= std::abs(r1 - r2)) return sphere_volume(std::min(r1, r2));
  const double t = r1 + r2 - d;
  return kPi * t * t * (d * d + 2 * d * (r1 + r2) - 3 * (r1 - r2) * (r1 - r2)) / (12 * d);
}

/// Radius of the circle where two spheres intersect (0 when apart or one inside the other).
inline double intersection_radius(double r1, double r2, double d) {
  if (d >= r1 + r2 || d <= std::abs(r1 - r2)) return 0;
  const double x = (d * d + r1 * r1 - r2 * r2) / (2 * d);
  return std::sqrt(std::max(0.0, r1 * r1 - x * x));
}

/// R̄ = 2 R_i R_j / (R_i + R_j): the sphere radius for equal spheres, the smaller radius' double
/// for very unequal ones (twice the reduced radius R*).
inline double harmonic_radius(double ri, double rj) { return 2 * ri * rj / (ri + rj); }

/// The contact definition shared by bond, conduct and carve (docs/architecture.md#contacts): two
/// spheres whose centres are d apart are in contact when their gap d − R_i − R_j is at most
/// tolerance · R̄ (overlapping and touching pairs always). "Touching" allows 1e-9 R̄ of round-off:
/// centres placed exactly one diameter apart (a lattice, a periodic image) come out a few ulps
/// of the cell size apart, and a zero tolerance must still bond them.
inline constexpr double kTouchingSlack = 1e-9;
inline bool in_contact(double d, double ri, double rj, double tolerance) {
  return d - ri - rj <= (tolerance + kTouchingSlack) * harmonic_radius(ri, rj);
}
/// The search reach that finds every pair in contact: R̄ ≤ 2 r_max.
inline double contact_reach(double rmax, double tolerance) {
  return (std::max(0.0, tolerance) + kTouchingSlack) * 2 * rmax;
}

}  // namespace tomodem::spatial
