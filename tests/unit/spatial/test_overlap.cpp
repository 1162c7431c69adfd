// Lens and cap volumes against numerical integration of the cross-sections (Simpson's rule) and
// their limiting cases; the contact definition against its formula.
#include <gtest/gtest.h>

#include <functional>

#include "tomodem/spatial/overlap.hpp"

using namespace tomodem::spatial;

namespace {
/// ∫ f over [a, b], composite Simpson with m (even) intervals.
double simpson(const std::function<double(double)>& f, double a, double b, int m) {
  const double h = (b - a) / m;
  double s = f(a) + f(b);
  for (int k = 1; k < m; ++k) s += (k % 2 ? 4 : 2) * f(a + k * h);
  return s * h / 3;
}
/// Lens volume as ∫ π ρ(z)² dz along the axis, ρ² = min(r1² − z², r2² − (z − d)²) where both
/// discs exist. The kink at the radical plane costs Simpson its order: O(h²) with 2·10⁵
/// intervals gives ~1e-9 relative.
double lens_by_integration(double r1, double r2, double d) {
  const auto area = [&](double z) {
    const double a = r1 * r1 - z * z, b = r2 * r2 - (z - d) * (z - d);
    return a > 0 && b > 0 ? kPi * std::min(a, b) : 0.0;
  };
  return simpson(area, std::max(-r1, d - r2), std::min(r1, d + r2), 200000);
}
}  // namespace

TEST(SpatialOverlap, LensVolumeMatchesIntegratedCrossSections) {
  const double cases[][3] = {{1, 1, 1.9}, {1, 1, 1.0}, {1, 1, 0.2}, {1, 10, 10.5}, {1, 10, 9.2}, {0.3, 0.5, 0.7}, {2, 0.2, 2.1}};
  for (const auto& c : cases) {
    const double expect = lens_by_integration(c[0], c[1], c[2]);
    EXPECT_NEAR(lens_volume(c[0], c[1], c[2]) / expect, 1.0, 1e-6) << c[0] << " " << c[1] << " " << c[2];
    EXPECT_DOUBLE_EQ(lens_volume(c[0], c[1], c[2]), lens_volume(c[1], c[0], c[2]));  // symmetric
  }
}

TEST(SpatialOverlap, LensVolumeLimitingCases) {
  const double r = 0.7;
  EXPECT_EQ(lens_volume(r, r, 2 * r), 0.0);              // touching
  EXPECT_EQ(lens_volume(r, 2 * r, 3.5 * r), 0.0);        // apart
  EXPECT_NEAR(lens_volume(r, 3 * r, r), sphere_volume(r), 1e-15);  // one inside the other
  // Equal spheres at d = r: two caps of height r/2, 2 · π (r/2)² (3r − r/2)/3 = 5πr³/12.
  EXPECT_NEAR(lens_volume(r, r, r), 5 * kPi * r * r * r / 12, 1e-14);
  // Continuous where one sphere just fits inside the other (d = R − r).
  EXPECT_NEAR(lens_volume(1, 2, 1 + 1e-9), sphere_volume(1), 1e-7);
}

TEST(SpatialOverlap, CapVolumeMatchesIntegralAndLimits) {
  const double r = 1.3;
  for (double d : {-1.2, -0.5, 0.0, 0.4, 1.1}) {
    // ∫_d^r π (r² − z²) dz in closed form, a formula other than the cap-height one.
    const double expect = kPi * (r * r * (r - d) - (r * r * r - d * d * d) / 3);
    EXPECT_NEAR(cap_volume(r, d), expect, 1e-12 * sphere_volume(r)) << d;
  }
  EXPECT_NEAR(cap_volume(r, 0), sphere_volume(r) / 2, 1e-14);
  EXPECT_EQ(cap_volume(r, r), 0.0);
  EXPECT_EQ(cap_volume(r, -r), sphere_volume(r));
  // A plane is the limit of a very large sphere: the lens with a sphere of radius R whose surface
  // lies at the same distance d tends to the cap (relative error O(r/R)).
  const double R = 1e5, d = 0.3;
  EXPECT_NEAR(lens_volume(r, R, R + d) / cap_volume(r, d), 1.0, 1e-4);
}

TEST(SpatialOverlap, IntersectionRadiusAndContactDefinition) {
  // Equal spheres: a² = r² − (d/2)².
  EXPECT_NEAR(intersection_radius(1, 1, 1.2), std::sqrt(1 - 0.36), 1e-15);
  EXPECT_EQ(intersection_radius(1, 2, 3.5), 0.0);
  EXPECT_EQ(intersection_radius(1, 3, 1.5), 0.0);  // inside
  // R̄ = 2 R_i R_j / (R_i + R_j): 1 and 3 give 1.5; gap tolerance 0.1 admits gaps up to 0.15.
  EXPECT_DOUBLE_EQ(harmonic_radius(1, 3), 1.5);
  EXPECT_TRUE(in_contact(4.0 + 0.149, 1, 3, 0.1));
  EXPECT_FALSE(in_contact(4.0 + 0.151, 1, 3, 0.1));
  EXPECT_TRUE(in_contact(4.0, 1, 3, 0.0));   // touching counts
  EXPECT_TRUE(in_contact(3.5, 1, 3, 0.0));   // overlapping
  // Touching allows kTouchingSlack R̄ (R̄ = 1.5 here) of round-off, and not more.
  EXPECT_TRUE(in_contact(4.0 + 1e-12, 1, 3, 0.0));
  EXPECT_FALSE(in_contact(4.0 + 2e-9, 1, 3, 0.0));
  EXPECT_GE(contact_reach(3, 0.1), 0.1 * harmonic_radius(3, 3));  // the search reach covers every R̄
}
