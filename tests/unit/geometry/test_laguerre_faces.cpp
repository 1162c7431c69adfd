// geometry::LaguerreFaces against cells computed by hand: the cube of a simple cubic lattice, the
// truncated octahedron of BCC, two unequal spheres in a periodic box (the face plane from the
// power-distance equality), and chains and layers in open cells (no tessellation: open faces).
#include <gtest/gtest.h>

#include <cmath>

#include "tomodem/dem/scene.hpp"
#include "tomodem/geometry/laguerre_faces.hpp"

using namespace tomodem;
using namespace tomodem::geometry;

namespace {
// Tolerance 1e-12 relative: CGAL's power centres of these lattices are exact up to round-off
// (the FCC volumes of test_laguerre.cpp agree to 1e-12).
constexpr double kTol = 1e-12;

/// Index of the lattice site at x (wrapped into the cell), -1 if none.
int site_at(const std::vector<Vec3>& x, Vec3 p, double L) {
  for (int k = 0; k < 3; ++k) p[k] -= L * std::floor(p[k] / L + 1e-9);
  for (std::size_t i = 0; i < x.size(); ++i)
    if (norm(x[i] - p) < 1e-9 * L) return int(i);
  return -1;
}
}  // namespace

// Simple cubic, spacing a: each cell is a cube of side a, the six faces a² to the nearest
// neighbours at ±a along the axes; the second shell (face diagonals) shares edges only.
TEST(LaguerreFaces, SimpleCubicFacesAreSquaresOfTheSpacing) {
  const int n = 3;
  const double a = 2e-6;
  const auto x = dem::lattice_sites(dem::LatticeKind::simple_cubic, n, a);
  const std::vector<double> r(x.size(), 0.6 * a);
  const LaguerreFaces faces(x, r, Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true));
  ASSERT_TRUE(faces.spans_space());
  for (int i = 0; i < int(x.size()); ++i)
    for (int k = 0; k < 3; ++k)
      for (double s : {-1.0, 1.0}) {
        Vec3 d;
        d[k] = s * a;
        const int j = site_at(x, x[std::size_t(i)] + d, n * a);
        ASSERT_GE(j, 0);
        EXPECT_NEAR(faces.area(i, j, d), a * a, kTol * a * a);
        EXPECT_NEAR(faces.area_at_distance(i, j, a), a * a, kTol * a * a);
      }
  // A diagonal neighbour: cells meet along an edge, no face of positive area.
  const Vec3 diag{a, a, 0};
  const int j = site_at(x, x[0] + diag, n * a);
  EXPECT_LT(faces.area(0, j, diag), 1e-12 * a * a);
}

// BCC, cube side a: the truncated octahedron of volume a³/2, edge e = a sqrt(2)/4; eight hexagons
// (3 sqrt(3)/2) e² = 3 sqrt(3) a²/16 to the neighbours at (±a/2, ±a/2, ±a/2) and six squares
// e² = a²/8 to those at ±a along the axes.
TEST(LaguerreFaces, BccFacesAreHexagonsAndSquaresOfTheTruncatedOctahedron) {
  const int n = 2;
  const double a = 1.0;
  const auto x = dem::lattice_sites(dem::LatticeKind::bcc, n, a);
  const std::vector<double> r(x.size(), 0.4);
  const LaguerreFaces faces(x, r, Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true));
  const double hexagon = 3 * std::sqrt(3.0) / 16 * a * a, square = a * a / 8;
  for (int i = 0; i < int(x.size()); ++i) {
    for (double sx : {-0.5, 0.5})
      for (double sy : {-0.5, 0.5})
        for (double sz : {-0.5, 0.5}) {
          const Vec3 d{sx * a, sy * a, sz * a};
          const int j = site_at(x, x[std::size_t(i)] + d, n * a);
          ASSERT_GE(j, 0);
          EXPECT_NEAR(faces.area(i, j, d), hexagon, kTol * a * a);
        }
    for (int k = 0; k < 3; ++k) {
      Vec3 d;
      d[k] = a;
      const int j = site_at(x, x[std::size_t(i)] + d, n * a);
      EXPECT_NEAR(faces.area(i, j, d), square, kTol * a * a);
    }
  }
}

// Two spheres r1 = 1.5, r2 = 0.5 at distance D = 2 along x in a periodic cube L = 4: the power
// planes |x − c1|² − r1² = |x − c2|² − r2² lie at d1 = (D² + r1² − r2²)/(2D) = 1.5 from sphere 1 on
// both sides (sphere 2 and its image at −2), so cell 1 is the slab 2 d1 × L × L = 48 and cell 2
// the rest, 16 (the midpoint would give 32 each); each face is the square L² = 16.
TEST(LaguerreFaces, UnequalSpheresMeetAtThePowerPlane) {
  const double L = 4, D = 2, r1 = 1.5, r2 = 0.5;
  const std::vector<Vec3> x{{1, 2, 2}, {1 + D, 2, 2}};
  const std::vector<double> r{r1, r2};
  const Cell cell = Cell::box({0, 0, 0}, {L, L, L}, true);
  const LaguerreFaces faces(x, r, cell);
  EXPECT_NEAR(faces.area(0, 1, {D, 0, 0}), L * L, kTol * L * L);
  EXPECT_NEAR(faces.area(0, 1, {D - L, 0, 0}), L * L, kTol * L * L);
  EXPECT_NEAR(faces.area(1, 0, {-D, 0, 0}), L * L, kTol * L * L);
  EXPECT_EQ(faces.area(0, 1, {D, 0.5, 0}), 0.0);  // no image of 1 there
  const double d1 = (D * D + r1 * r1 - r2 * r2) / (2 * D);
  const Tessellation t = laguerre(x, r, cell);
  EXPECT_NEAR(t.cell_volume[0], 2 * d1 * L * L, kTol * L * L * L);
  EXPECT_NEAR(t.cell_volume[1], L * L * L - 2 * d1 * L * L, kTol * L * L * L);
}

// A chain along x and a layer in z = 0 in an open cell do not span space: no tessellation (CGAL's
// would not be three-dimensional), every face open. A chain in a cell periodic along y and z spans.
TEST(LaguerreFaces, ChainsAndLayersInOpenCellsHaveOpenFaces) {
  const Cell open = Cell::box({-10, -10, -10}, {10, 10, 10}, false);
  const std::vector<Vec3> chain{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  const std::vector<Vec3> layer{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const std::vector<double> r(4, 0.6);
  for (const auto* x : {&chain, &layer}) {
    const LaguerreFaces faces(*x, r, open);
    EXPECT_FALSE(faces.spans_space());
    EXPECT_EQ(faces.area(0, 1, {1, 0, 0}), HUGE_VAL);
    EXPECT_EQ(faces.area_at_distance(0, 1, 1), HUGE_VAL);
  }
  Cell yz = Cell::box({-10, 0, 0}, {10, 2, 2}, true);
  yz.periodic[0] = false;
  EXPECT_TRUE(spans_space(chain, yz));
  EXPECT_FALSE(spans_space({}, open));
}
