// The hierarchical grid (libs/spatial, several levels) must give exactly the pair set of the
// linked cells (one level: Simulation's own loop over the grid), including periodic image codes,
// on wide polydisperse configurations: periodic, sheared periodic, mixed and open boxes.
// Compared through Simulation's own neighbour list.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>

#include "tomodem/dem/simulation.hpp"
#include "tomodem/spatial/grid.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::spatial;

namespace {

using PairSet = std::set<std::tuple<int, int, int>>;

ContactModel linear_model() {
  ContactModel m;
  m.normal = NormalLaw::linear;
  Material mat;
  mat.name = "a";
  mat.density = 1000;
  m.materials = {mat};
  m.finalize();
  m.pair(0, 0).k_n = 1e3;
  m.finalize();
  return m;
}

/// Random spheres (overlaps allowed: the lists are geometric) with log-uniform radii over
/// [rmin, ratio * rmin] in the cell.
Particles random_particles(int n, double rmin, double ratio, const Cell& cell, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Particles p;
  for (int i = 0; i < n; ++i) {
    const Vec3 s{u(rng), u(rng), u(rng)};
    const double r = rmin * std::pow(ratio, u(rng));
    p.add(cell.origin + cell.h * s, r, 1000, 0);
  }
  return p;
}

PairSet pairs_with(NeighborSearch mode, const Particles& p, const Cell& cell, double skin, int threads = 1) {
  set_neighbor_search(mode);
  Settings s;
  s.skin = skin;
  s.threads = threads;
  Simulation sim(p, cell, linear_model(), s);
  sim.set_time_step(1e-12);
  sim.measure();  // builds the list
  const auto st = sim.engine_state();
  PairSet out;
  for (std::size_t i = 0; i + 1 < st.start.size(); ++i)
    for (int k = st.start[i]; k < st.start[i + 1]; ++k) {
      EXPECT_TRUE(int(i) < st.j[std::size_t(k)] || (int(i) == st.j[std::size_t(k)] && st.image[std::size_t(k)] > 13));
      const bool fresh = out.emplace(int(i), st.j[std::size_t(k)], st.image[std::size_t(k)]).second;
      EXPECT_TRUE(fresh) << "duplicate pair " << i << " " << st.j[std::size_t(k)];
    }
  set_neighbor_search(NeighborSearch::automatic);
  return out;
}

void expect_same(const Particles& p, const Cell& cell, double skin) {
  const PairSet a = pairs_with(NeighborSearch::linked_cells, p, cell, skin);
  const PairSet b = pairs_with(NeighborSearch::hgrid, p, cell, skin);
  EXPECT_GT(a.size(), p.size());  // the configuration is dense enough to test something
  EXPECT_EQ(a.size(), b.size());
  EXPECT_TRUE(a == b);
  // Threads search ranges of particles separately: the same list for any count.
  EXPECT_TRUE(pairs_with(NeighborSearch::hgrid, p, cell, skin, 3) == b);
}

}  // namespace

TEST(Hgrid, PeriodicCubeRatio10SamePairsAsLinkedCells) {
  const Cell cell = Cell::box({0, 0, 0}, {1, 1, 1}, true);
  expect_same(random_particles(3000, 0.01, 10, cell, 1), cell, 0.002);
}

TEST(Hgrid, PeriodicSheared1to20SamePairsAsLinkedCells) {
  Cell cell = Cell::box({-0.5, 0, 0}, {0.5, 1.2, 0.8}, true);
  cell.h(0, 1) = 0.3;  // tilted cell: fractional bins and perpendicular widths
  cell.h(1, 2) = -0.1;
  expect_same(random_particles(3000, 0.006, 20, cell, 2), cell, 0.001);
}

TEST(Hgrid, OpenBoxSamePairsAsLinkedCells) {
  const Cell cell = Cell::box({0, 0, 0}, {1, 2, 1}, false);
  expect_same(random_particles(4000, 0.01, 12, cell, 3), cell, 0.002);
}

TEST(Hgrid, MixedPeriodicitySamePairsAsLinkedCells) {
  Cell cell = Cell::box({0, 0, 0}, {1, 1, 1}, true);
  cell.periodic[2] = false;
  expect_same(random_particles(3000, 0.012, 8, cell, 4), cell, 0.002);
}

TEST(Hgrid, SmallCellWithSelfImagesSamePairsAsLinkedCells) {
  // A cell only a few large diameters wide: images ±1 of the same particle are neighbours.
  const Cell cell = Cell::box({0, 0, 0}, {0.1, 0.1, 0.1}, true);
  expect_same(random_particles(300, 0.002, 10, cell, 5), cell, 0.001);
}

TEST(Hgrid, CoplanarOpenScene1to1e5SamePairsAsLinkedCells) {
  // Degenerate extent (all centres on one line) and a huge size ratio, as a wall-like sphere.
  Particles p;
  p.add({0, 0, 1.05e-3}, 1e-3, 1000, 0);
  p.add({0, 0, -100}, 100, 1000, 0);
  p.add({0, 0, 3.2e-3}, 1e-3, 1000, 0);
  const Cell cell = Cell::box({-1, -1, -201}, {1, 1, 1}, false);
  const PairSet a = pairs_with(NeighborSearch::linked_cells, p, cell, 1e-4);
  const PairSet b = pairs_with(NeighborSearch::hgrid, p, cell, 1e-4);
  EXPECT_EQ(a.size(), 1u);  // only the first small sphere is within the skin of the big one
  EXPECT_TRUE(a == b);
}

TEST(Hgrid, AutomaticChoiceFollowsSizeRatio) {
  EXPECT_FALSE(use_hgrid({1.0, 1.5, 2.0}));
  EXPECT_TRUE(use_hgrid({1.0, 1.5, 10.0}));
  const auto lv = hgrid_levels({1.0, 1.9, 2.5, 3.9, 10.0});
  ASSERT_EQ(lv.size(), 4u);  // (1,2], (2,4], (4,8], (8,16]
  EXPECT_DOUBLE_EQ(lv[0], 1.9);
  EXPECT_DOUBLE_EQ(lv[1], 3.9);
  EXPECT_DOUBLE_EQ(lv[2], 0.0);  // empty level
  EXPECT_DOUBLE_EQ(lv[3], 10.0);
}
