// Exact union volume of spheres (spatial/union_volume.hpp) against analytic cases and an
// independent quadrature.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tomodem/spatial/overlap.hpp"
#include "tomodem/spatial/union_volume.hpp"

using namespace tomodem;
using namespace tomodem::spatial;

namespace {
Cell open_box(double L) { return Cell::box({-L, -L, -L}, {L, L, L}, false); }
// Round-off of the closed forms (sums of a few dozen O(R³) terms): 1e-12 relative.
constexpr double kExact = 1e-12;
}  // namespace

TEST(UnionVolume, LoneSphereAndOnePlane) {
  const double R = 1.3;
  EXPECT_NEAR(clip_sphere(R, {}).volume, sphere_volume(R), kExact * sphere_volume(R));
  EXPECT_NEAR(clip_sphere(R, {}).sphere_area, 4 * kPi * R * R, kExact * R * R);
  // One plane at h: the sphere less the cap beyond it; spherical area 2πR(R + h).
  for (double h : {-0.9, -0.3, 0.0, 0.2, 0.7, 1.2}) {
    const ClippedSphere c = clip_sphere(R, {{Vec3{0.6, 0.0, 0.8}, h}});
    EXPECT_NEAR(c.volume, sphere_volume(R) - cap_volume(R, h), kExact * sphere_volume(R)) << h;
    EXPECT_NEAR(c.sphere_area, 2 * kPi * R * (R + h), 1e-10 * R * R) << h;
  }
  EXPECT_EQ(clip_sphere(R, {{Vec3{0, 0, 1}, -R}}).volume, 0.0);
}

TEST(UnionVolume, TwoSpheresEqualThePairwiseFormula) {
  // Two spheres: the pairwise formula Σ V − lens is exact.
  for (double d : {0.5, 1.2, 1.9}) {
    const std::vector<Vec3> x{{0, 0, 0}, {d * 0.48, d * 0.6, d * 0.64}};
    const std::vector<double> r{1.0, 0.8};
    const UnionVolume u = union_volume(x, r, open_box(10));
    const double want = sphere_volume(1.0) + sphere_volume(0.8) - lens_volume(1.0, 0.8, d);
    EXPECT_NEAR(u.union_volume, want, kExact * want) << d;
    EXPECT_NEAR(u.pairwise, want, kExact * want) << d;
  }
}

TEST(UnionVolume, ThreeCollinearSpheresWhereThePairwiseFormulaFails) {
  // Equal spheres at 0, d, 2d with d < R: B1 ∩ B3 lies inside B2 (|x − c2|² is the mean of
  // |x − c1|² and |x − c3|² less d²), so the union is 3V − 2 lens(d); the pairwise formula also
  // subtracts lens(2d), the triple overlap, and is low by exactly that.
  const double R = 1.0, d = 0.7;
  const std::vector<Vec3> x{{0, 0, 0}, {d, 0, 0}, {2 * d, 0, 0}};
  const std::vector<double> r(3, R);
  const UnionVolume u = union_volume(x, r, open_box(10));
  const double want = 3 * sphere_volume(R) - 2 * lens_volume(R, R, d);
  EXPECT_NEAR(u.union_volume, want, kExact * want);
  EXPECT_NEAR(want - u.pairwise, lens_volume(R, R, 2 * d), kExact * want);
  EXPECT_GT(lens_volume(R, R, 2 * d), 0.01 * want);  // the case really has a triple overlap
}

TEST(UnionVolume, ThreeSpheresInATriangleAgainstMonteCarlo) {
  // No closed form: a Monte Carlo estimate of the union in its bounding box, 4e6 points.
  const std::vector<Vec3> x{{0, 0, 0}, {1.3, 0, 0}, {0.6, 1.1, 0.2}};
  const std::vector<double> r{1.0, 0.9, 0.8};
  const UnionVolume u = union_volume(x, r, open_box(10));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(-1, 2.2), uy(-1, 1.9), uz(-1, 1.0);
  const double box = 3.2 * 2.9 * 2.0;
  const long N = 4000000;
  long hit = 0;
  for (long k = 0; k < N; ++k) {
    const Vec3 p{ux(rng), uy(rng), uz(rng)};
    for (int s = 0; s < 3; ++s)
      if (norm2(p - x[std::size_t(s)]) < r[std::size_t(s)] * r[std::size_t(s)]) {
        ++hit;
        break;
      }
  }
  const double f = double(hit) / double(N), mc = f * box, sd = box * std::sqrt(f * (1 - f) / double(N));
  EXPECT_NEAR(u.union_volume, mc, 4 * sd);  // 4 standard errors of the estimate
  // The triple overlap is real here: the pairwise value falls outside that band.
  EXPECT_GT(std::abs(u.pairwise - mc), 10 * sd);
}

TEST(UnionVolume, PeriodicSimpleCubicIsBallInCube) {
  // SC lattice, spacing a, R = 0.75a: power cells are the cubes, so the union per cell is
  // V(ball ∩ cube), with the edges of the cube cutting the ball (R > a/√2: the caps overlap,
  // second neighbours at a√2 < 2R). Reference: the z-integral of the exact slice area
  // A(z) = ∫ 2 min(a/2, sqrt(ρ² − x²)) dx over |x| < min(a/2, ρ), both by composite Simpson
  // (the slice area is smooth except at two kinks, which a fine grid resolves to < 1e-7).
  const double a = 1.0, R = 0.75, hw = a / 2;
  auto slice = [&](double z) {
    const double rho2 = R * R - z * z;
    if (rho2 <= 0) return 0.0;
    const double xm = std::min(hw, std::sqrt(rho2));
    const int m = 4000;
    double s = 0;
    for (int k = 0; k <= m; ++k) {
      const double xx = -xm + 2 * xm * k / m;
      const double w = (k == 0 || k == m) ? 1 : (k % 2 ? 4 : 2);
      s += w * 2 * std::min(hw, std::sqrt(std::max(0.0, rho2 - xx * xx)));
    }
    return s * (2 * xm / m) / 3;
  };
  double ref = 0;
  const int m = 4000;
  for (int k = 0; k <= m; ++k) {
    const double z = -hw + a * k / m;
    ref += ((k == 0 || k == m) ? 1 : (k % 2 ? 4 : 2)) * slice(z);
  }
  ref *= (a / m) / 3;
  std::vector<Vec3> x;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) x.push_back({(i + 0.5) * a, (j + 0.5) * a, (k + 0.5) * a});
  const std::vector<double> r(x.size(), R);
  const Cell cell = Cell::box({0, 0, 0}, {3 * a, 3 * a, 3 * a}, true);
  const UnionVolume u = union_volume(x, r, cell);
  EXPECT_NEAR(u.union_volume / 27, ref, 1e-6 * ref);
  EXPECT_NEAR(union_relative_density(x, r, cell), ref / (a * a * a), 1e-6);
  EXPECT_LT(u.pairwise, u.union_volume);  // the edges' triple overlaps are subtracted twice there
}

TEST(UnionVolume, RandomOverlappingSpheresAgainstMonteCarloInAPeriodicCell) {
  // 40 spheres (radii 0.2–0.35) at random in a periodic unit cube, heavy overlaps: the exact
  // union against 2e6 Monte Carlo points (nearest-image distance to every centre).
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u01(0, 1);
  std::vector<Vec3> x;
  std::vector<double> r;
  for (int k = 0; k < 40; ++k) x.push_back({u01(rng), u01(rng), u01(rng)}), r.push_back(0.2 + 0.15 * u01(rng));
  const Cell cell = Cell::box({0, 0, 0}, {1, 1, 1}, true);
  const double rho = union_relative_density(x, r, cell);
  const long N = 2000000;
  long hit = 0;
  for (long k = 0; k < N; ++k) {
    const Vec3 p{u01(rng), u01(rng), u01(rng)};
    for (std::size_t s = 0; s < x.size(); ++s) {
      Vec3 d = p - x[s];
      for (int c = 0; c < 3; ++c) d[c] -= std::round(d[c]);
      if (norm2(d) < r[s] * r[s]) {
        ++hit;
        break;
      }
    }
  }
  const double f = double(hit) / double(N), sd = std::sqrt(f * (1 - f) / double(N));
  EXPECT_NEAR(rho, f, 4 * sd);
}
