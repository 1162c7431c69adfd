// The neighbour search against brute force O(N²) over all images −1..1: polydisperse spheres
// (size ratio 1:10) in cubic and sheared (triclinic) cells, periodic and partly open, with one
// grid level and with the hierarchical grid, on one and several threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "tomodem/core/error.hpp"
#include "tomodem/spatial/grid.hpp"

using namespace tomodem;
using namespace tomodem::spatial;

namespace {

using PairSet = std::set<std::tuple<int, int, int>>;  // (i, j, image code), i ≤ j

struct Scene {
  std::vector<Vec3> x;
  std::vector<double> r;
  Cell cell;
};

/// n spheres, radii log-uniform in [rmin, rmax], centres uniform in the cell (fractional).
Scene random_scene(int n, double rmin, double rmax, const Mat3& h, bool px, bool py, bool pz, uint64_t seed) {
  Scene s;
  s.cell.h = h;
  s.cell.origin = {0.3, -0.2, 0.1};
  s.cell.periodic[0] = px, s.cell.periodic[1] = py, s.cell.periodic[2] = pz;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < n; ++i) {
    s.x.push_back(s.cell.origin + h * Vec3{u(rng), u(rng), u(rng)});
    s.r.push_back(rmin * std::pow(rmax / rmin, u(rng)));
  }
  return s;
}

/// Every (i, j, n) with |x_j + H n − x_i| < r_i + r_j + extra, n in −1..1 along periodic
/// directions, i < j, or i == j with n in the positive half (code > 13).
PairSet brute_force(const Scene& s, double extra) {
  PairSet out;
  for (std::size_t i = 0; i < s.x.size(); ++i)
    for (std::size_t j = i; j < s.x.size(); ++j)
      for (int c = 0; c < 27; ++c) {
        const Image n = image_of_code(c);
        bool ok = !(i == j && c <= 13);
        for (int k = 0; k < 3; ++k) ok = ok && (s.cell.periodic[k] || n[std::size_t(k)] == 0);
        if (!ok) continue;
        const Vec3 d = s.x[j] + s.cell.h * as_vector(n) - s.x[i];
        const double rc = s.r[i] + s.r[j] + extra;
        if (dot(d, d) < rc * rc) out.insert({int(i), int(j), c});
      }
  return out;
}

PairSet grid_pairs(const Scene& s, double extra, bool hierarchical, int threads) {
  const Grid g(s.x, s.r, s.cell, extra, hierarchical);
  const auto shift = image_shifts(s.cell.h);
  std::vector<int32_t> start, j;
  std::vector<uint8_t> code;
  half_list(g, s.x, s.r, shift.data(), extra, start, j, code, threads);
  PairSet out;
  for (std::size_t i = 0; i + 1 < start.size(); ++i)
    for (int32_t k = start[i]; k < start[i + 1]; ++k) {
      EXPECT_TRUE(out.insert({int(i), j[std::size_t(k)], code[std::size_t(k)]}).second) << "pair listed twice";
      if (k > start[i]) {  // rows sorted by (j, code)
        EXPECT_LT(std::make_pair(j[std::size_t(k - 1)], code[std::size_t(k - 1)]), std::make_pair(j[std::size_t(k)], code[std::size_t(k)]));
      }
    }
  return out;
}

Mat3 sheared(double L) {
  Mat3 h = Mat3::diagonal({L, 0.8 * L, 1.1 * L});
  h(0, 1) = 0.35 * L;  // b leans along x
  h(0, 2) = -0.2 * L;  // c along x and y
  h(1, 2) = 0.3 * L;
  return h;
}

void check_all(const Scene& s, double extra) {
  const PairSet expect = brute_force(s, extra);
  ASSERT_GT(expect.size(), s.x.size() / 2);  // the scene is dense enough to test something
  EXPECT_TRUE(grid_pairs(s, extra, false, 1) == expect) << "one level";
  EXPECT_TRUE(grid_pairs(s, extra, true, 1) == expect) << "hierarchical";
  EXPECT_TRUE(grid_pairs(s, extra, true, 3) == expect) << "hierarchical, 3 threads";
}

}  // namespace

TEST(SpatialGrid, PolydispersePeriodicCubicCellMatchesBruteForce) {
  const Scene s = random_scene(600, 0.01, 0.1, Mat3::diagonal({1, 1, 1}), true, true, true, 1);
  check_all(s, 0.005);
}

TEST(SpatialGrid, PolydisperseShearedTriclinicCellMatchesBruteForce) {
  const Scene s = random_scene(600, 0.01, 0.1, sheared(1.0), true, true, true, 2);
  check_all(s, 0.0);
}

TEST(SpatialGrid, PartlyOpenShearedCellMatchesBruteForce) {
  const Scene s = random_scene(500, 0.01, 0.1, sheared(1.0), true, false, true, 3);
  check_all(s, 0.01);
}

TEST(SpatialGrid, SmallCellWithSelfImagesMatchesBruteForce) {
  // A cell about three of the largest diameters wide: pairs through several images, and a
  // sphere overlaps its own image.
  const Scene s = random_scene(60, 0.03, 0.3, sheared(1.0), true, true, true, 4);
  check_all(s, 0.02);
}

TEST(SpatialGrid, HierarchicalGridUsesLevelsOfDoublingRadius) {
  const Scene s = random_scene(200, 0.01, 0.1, Mat3::diagonal({1, 1, 1}), true, true, true, 5);
  const Grid g(s.x, s.r, s.cell, 0.0, true);
  const double rmin = *std::min_element(s.r.begin(), s.r.end()), rmax = *std::max_element(s.r.begin(), s.r.end());
  // Level l holds (rmin 2^l, rmin 2^(l+1)]: as many levels as doublings needed to reach rmax.
  EXPECT_EQ(g.levels(), std::max(1, int(std::ceil(std::log2(rmax / rmin)))));
  for (std::size_t i = 0; i < s.r.size(); ++i) {
    const double lo = rmin * std::pow(2.0, g.level(i)), hi = 2 * lo;
    EXPECT_TRUE(s.r[i] <= hi && (g.level(i) == 0 || s.r[i] > lo)) << s.r[i] << " at level " << g.level(i);
  }
  const Grid one(s.x, s.r, s.cell, 0.0, false);
  EXPECT_EQ(one.levels(), 1);
}

TEST(SpatialGrid, PairsWithinTakesUnwrappedPositionsAndReturnsTheirImages) {
  Scene s = random_scene(400, 0.01, 0.1, sheared(1.0), true, true, false, 6);
  // Move particles by whole lattice vectors: the pairs must be the same, their images shifted.
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> shift(-2, 2);
  std::vector<Vec3> x0 = s.x;
  for (auto& xi : x0) xi += s.cell.h * Vec3{double(shift(rng)), double(shift(rng)), 0.0};
  const double extra = 0.004;
  const std::vector<Pair> pairs = pairs_within(x0, s.r, s.cell, extra);
  // Independent check: for i < j, every lattice vector n (|n_k| ≤ 5) within reach.
  std::set<std::tuple<int, int, int, int, int>> expect, got;
  for (std::size_t i = 0; i < x0.size(); ++i)
    for (std::size_t j = i + 1; j < x0.size(); ++j)
      for (int a = -5; a <= 5; ++a)
        for (int b = -5; b <= 5; ++b) {
          const Vec3 d = x0[j] + s.cell.h * Vec3{double(a), double(b), 0.0} - x0[i];
          if (norm(d) < s.r[i] + s.r[j] + extra) expect.insert({int(i), int(j), a, b, 0});
        }
  for (const Pair& q : pairs) {
    got.insert({q.i, q.j, q.image[0], q.image[1], q.image[2]});
    const Vec3 d = x0[std::size_t(q.j)] + s.cell.h * as_vector(q.image) - x0[std::size_t(q.i)];
    EXPECT_NEAR(q.distance, norm(d), 1e-12);
  }
  ASSERT_GT(expect.size(), 100u);
  EXPECT_TRUE(got == expect);
}

TEST(SpatialImage, CodesAndMinimumImage) {
  for (int c = 0; c < kImageCodes; ++c) {
    EXPECT_EQ(image_code(image_of_code(c)), c);
    const Image n = image_of_code(c), m = image_of_code(opposite_image(c));
    for (int k = 0; k < 3; ++k) EXPECT_EQ(n[std::size_t(k)], -m[std::size_t(k)]);
  }
  EXPECT_EQ(image_code({2, 0, 0}), -1);
  EXPECT_EQ(image_of_code(kCentreImage), (Image{0, 0, 0}));
  Cell c;
  c.h = sheared(2.0);
  c.periodic[0] = c.periodic[1] = true;
  const Vec3 xi{0.1, 0.1, 0.1};
  // j placed one cell vector a and minus b away from a point near i: its nearest image is −a + b.
  const Vec3 xj = xi + Vec3{0.05, -0.02, 0.0} + c.h.col(0) - c.h.col(1);
  EXPECT_EQ(minimum_image(c, c.h.inverse(), xi, xj), (Image{-1, 1, 0}));
}

TEST(SpatialGrid, ContactsWithinKeepsThePairsWithinTheGapTolerance) {
  // Unit spheres at x = 0, 2 (touching) and 4.5 (gap 0.5 = 0.5 R̄ from the second) in an open box:
  // tolerance 0 finds the touching pair, 0.5 both, 0.49 still one.
  const Cell c = Cell::box({-2, -2, -2}, {7, 2, 2}, false);
  const std::vector<Vec3> x = {{0, 0, 0}, {2, 0, 0}, {4.5, 0, 0}};
  const std::vector<double> r = {1, 1, 1};
  EXPECT_EQ(contacts_within(x, r, c, 0.0).size(), 1u);
  EXPECT_EQ(contacts_within(x, r, c, 0.49).size(), 1u);
  const std::vector<Pair> both = contacts_within(x, r, c, 0.5);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_NEAR(both[1].distance, 2.5, 1e-12);
  EXPECT_TRUE(contacts_within({x[0]}, {1.0}, c, 1.0).empty());
}

TEST(SpatialImage, ShortestBranchTakesTheNearestImageAlongPeriodicAxesOnly) {
  // Unit box periodic along x only: j at x = 0.9 is 0.2 behind i at 0.1 through the −x image;
  // along the open y it stays 0.8 away.
  Cell c;
  c.h = Mat3::identity();
  c.periodic[0] = true;
  c.periodic[1] = c.periodic[2] = false;
  Image n{9, 9, 9};
  const Vec3 d = shortest_branch(c, {0.1, 0.1, 0.5}, {0.9, 0.9, 0.5}, &n);
  EXPECT_NEAR(d.x, -0.2, 1e-15);
  EXPECT_NEAR(d.y, 0.8, 1e-15);
  EXPECT_EQ(d.z, 0.0);
  EXPECT_EQ(n, (Image{-1, 0, 0}));
}

TEST(SpatialImage, WrapIntoCellReturnsTheLatticeVectorsSubtracted) {
  Cell c;
  c.h = sheared(1.0);
  c.origin = {1, 2, 3};
  c.periodic[0] = c.periodic[2] = true;
  std::vector<Vec3> x0 = {c.origin + c.h * Vec3{1.5, 0.5, -0.25}, c.origin + c.h * Vec3{0.5, 1.7, 2.5}};
  std::vector<Vec3> x = x0;
  const std::vector<Image> w = wrap_into_cell(x, c);
  EXPECT_EQ(w[0], (Image{1, 0, -1}));
  EXPECT_EQ(w[1], (Image{0, 0, 2}));  // y is open: not wrapped
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Vec3 back = x[i] + c.h * as_vector(w[i]);
    EXPECT_NEAR(norm(back - x0[i]), 0.0, 1e-12);
  }
}

// Hostile review D2/D8: bond, carve and sinter refuse a packing file with a pair overlapping by
// more than half the smaller radius (coincident particles included), as a scene's start does;
// the pair is found across a periodic face too. Half a radius or less passes.
TEST(StartOverlaps, StrongOverlapRefusedNamingThePair) {
  Cell cell;
  cell.h = Mat3::diagonal({10, 10, 10});
  cell.periodic[0] = cell.periodic[1] = cell.periodic[2] = true;
  const std::vector<double> r = {1, 1, 1};
  auto message = [&](const std::vector<Vec3>& x) -> std::string {
    try {
      check_start_overlaps(x, r, cell, "in.h5");
    } catch (const tomodem::InputError& e) {
      EXPECT_EQ(e.file(), "in.h5");
      EXPECT_EQ(e.field(), "/particles/position");
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message({{1, 1, 1}, {2.5, 1, 1}, {5, 5, 5}}), "");  // overlap 0.5 R: allowed
  const std::string same = message({{1, 1, 1}, {5, 5, 5}, {1, 1, 1}});
  EXPECT_NE(same.find("particles 0 and 2 overlap by 2"), std::string::npos) << same;
  EXPECT_NE(same.find("same position"), std::string::npos) << same;
  const std::string wrapped = message({{0.2, 1, 1}, {5, 5, 5}, {9.2, 1, 1}});  // 1 apart through x = 0
  EXPECT_NE(wrapped.find("particles 0 and 2 overlap by 1 of the smaller radius"), std::string::npos) << wrapped;
}

// A pair joined by an intact bond (a sintered neck) may overlap deeply: not refused.
TEST(StartOverlaps, BondedPairIsSkipped) {
  Cell cell;
  cell.h = Mat3::diagonal({10, 10, 10});
  cell.periodic[0] = cell.periodic[1] = cell.periodic[2] = true;
  const std::vector<Vec3> x = {{1, 1, 1}, {2, 1, 1}};
  const std::vector<double> r = {1, 1};
  BondTable b;
  b.i = {0};
  b.j = {1};
  b.radius = {0.5};
  b.rest_length = {1};
  b.state = {BondTable::intact};
  b.broken_at = {0};
  EXPECT_NO_THROW(check_start_overlaps(x, r, cell, "in.h5", &b));
  b.state = {BondTable::broken};
  EXPECT_THROW(check_start_overlaps(x, r, cell, "in.h5", &b), tomodem::InputError);
}
