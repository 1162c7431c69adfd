// Laguerre tessellation: lattice cells have the analytic volume; on a random polydisperse
// packing the cells tile the periodic box (sum = box volume to 1e-9, issue 3).
#include <gtest/gtest.h>

#include <random>

#include "tomodem/dem/scene.hpp"
#include "tomodem/geometry/laguerre.hpp"
#include "tomodem/geometry/pack.hpp"

using namespace tomodem;
using namespace tomodem::geometry;

TEST(Laguerre, FccCellsAreRhombicDodecahedraOfVolumeASquaredOver4) {
  const int n = 4;
  const double a = 1.0;
  const auto x = dem::lattice_sites(dem::LatticeKind::fcc, n, a);
  std::vector<double> r(x.size(), 0.3);
  const Cell cell = Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true);
  const auto t = laguerre(x, r, cell);
  for (double v : t.cell_volume) EXPECT_NEAR(v, a * a * a / 4, 1e-12);
}

TEST(Laguerre, RandomPolydisperseCellsSumToBoxVolume) {
  const Cell cell = Cell::box({0, 0, 0}, {1, 1, 1}, true);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> r;
  for (int i = 0; i < 3000; ++i) r.push_back(0.01 * std::pow(5.0, u(rng)));
  const auto x = insert_random(r, {}, {}, cell, 9);
  const auto t = laguerre(x, r, cell);
  EXPECT_LT(std::abs(t.total_volume - 1.0), 1e-9);  // issue 3 criterion
  for (std::size_t i = 0; i < r.size(); ++i) {
    EXPECT_GT(t.cell_volume[i], 0);
    EXPECT_LE(t.local_solid_fraction[i], 1.0);  // a non-overlapping sphere lies inside its cell
  }
}

// A box of a few large particles: the first margin (two diameters and two spacings) is wider than
// the box, so every one of the 27 images is needed; this used to fail with "0 vs 0 m^3".
TEST(Laguerre, FewParticlesInASmallBoxUseEveryImage) {
  for (const int n : {2, 8, 40}) {
    const Cell cell = Cell::box({0, 0, 0}, {1, 1, 1}, true);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<double> r;
    for (int i = 0; i < n; ++i) r.push_back(0.25 * std::cbrt(1.0 / n) * (0.8 + 0.4 * u(rng)));
    const auto x = insert_random(r, {}, {}, cell, 3);
    const auto t = laguerre(x, r, cell);
    EXPECT_LT(std::abs(t.total_volume - 1.0), 1e-9) << n << " particles";
  }
}
