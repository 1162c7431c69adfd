// tomodem-bond's geometry: lens volumes, neighbour pairs against brute force, density,
// neck rules, phase-pair rules, clusters and their wrapping of the periodic cell.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "../../validation/mechanics/networks.hpp"
#include "tomodem/mechanics/bonding.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

TEST(Lens, EqualSpheresMatchClosedForm) {
  // Two equal spheres: V = π (4r + d)(2r − d)² / 12 (exact geometry; round-off only).
  const double r = 1.3;
  for (double d : {0.1, 1.0, 2.0, 2.5}) {
    const double V = M_PI * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12;
    EXPECT_NEAR(lens_volume(r, r, d) / V, 1.0, 1e-12) << d;
    EXPECT_NEAR(intersection_radius(r, r, d), std::sqrt(r * r - d * d / 4), 1e-12);
  }
  EXPECT_EQ(lens_volume(r, r, 2 * r), 0.0);
  EXPECT_EQ(intersection_radius(1, 2, 3.5), 0.0);
  EXPECT_NEAR(lens_volume(1, 3, 1.0), 4.0 / 3.0 * M_PI, 1e-12);  // small sphere inside
}

TEST(Lens, UnequalSpheresMatchMonteCarlo) {
  // Monte Carlo in the bounding box of the smaller sphere, 4e6 samples: standard error ~0.2%,
  // tolerance 1% (5 sigma).
  const double r1 = 1.0, r2 = 0.6, d = 1.2;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-r2, r2);
  long in = 0;
  const long n = 4000000;
  for (long k = 0; k < n; ++k) {
    const double x = d + u(rng), y = u(rng), z = u(rng);
    if ((x - d) * (x - d) + y * y + z * z < r2 * r2 && x * x + y * y + z * z < r1 * r1) ++in;
  }
  const double mc = 8 * r2 * r2 * r2 * double(in) / double(n);
  EXPECT_NEAR(lens_volume(r1, r2, d) / mc, 1.0, 0.01);
}

TEST(NeighborPairs, SameSetAsBruteForceInShearedPeriodicCell) {
  // Random spheres in a sheared, fully periodic cell (and a mixed open/periodic one): the linked
  // cells find exactly the pairs the all-pairs, all-images search finds.
  for (bool mixed : {false, true}) {
    Packing p;
    p.cell = Cell::box({0.1, -0.2, 0.3}, {4.1, 3.3, 5.3}, true);
    p.cell.h(0, 1) = 0.7;
    p.cell.h(0, 2) = -0.4;
    p.cell.h(1, 2) = 0.3;
    if (mixed) p.cell.periodic[1] = false;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0, 1), rr(0.2, 0.45);
    for (int k = 0; k < 300; ++k) {
      const Vec3 s{u(rng) * 1.3 - 0.15, u(rng), u(rng)};  // some outside the cell (unwrapped)
      p.particles.position.push_back(p.cell.origin + p.cell.h * s);
      p.particles.radius.push_back(rr(rng));
      p.particles.phase.push_back(0);
    }
    const double reach = 0.05;
    const auto pairs = neighbor_pairs(p, reach);
    std::set<std::tuple<int, int, int, int, int>> fast, brute;
    for (const auto& q : pairs) {
      fast.insert({q.i, q.j, q.image[0], q.image[1], q.image[2]});
      const Image im = q.image;
      const Vec3 d = p.particles.position[q.j] + p.cell.h * Vec3{double(im[0]), double(im[1]), double(im[2])} -
                     p.particles.position[q.i];
      EXPECT_NEAR(norm(d), q.distance, 1e-12);
    }
    for (int i = 0; i < 300; ++i)
      for (int j = i + 1; j < 300; ++j)
        for (int a = -2; a <= 2; ++a)
          for (int b = -2; b <= 2; ++b)
            for (int c = -2; c <= 2; ++c) {
              if ((!p.cell.periodic[1] && b != 0)) continue;
              const Vec3 d = p.particles.position[j] + p.cell.h * Vec3{double(a), double(b), double(c)} -
                             p.particles.position[i];
              if (norm(d) < p.particles.radius[i] + p.particles.radius[j] + reach) brute.insert({i, j, a, b, c});
            }
    EXPECT_GT(brute.size(), 100u);
    EXPECT_EQ(fast, brute) << (mixed ? "mixed" : "periodic");
  }
}

TEST(RelativeDensity, SimpleCubicLatticeWithAndWithoutOverlaps) {
  // Touching spheres: π/6. Spacing s < 2R: (4/3 π R³ − 3 lens(s)) / s³ (three lenses per site).
  const double R = 1.0;
  EXPECT_NEAR(relative_density(test::lattice("simple_cubic", 4, 2 * R, R)), M_PI / 6, 1e-12);
  const double s = 1.9;
  const double expect = (4.0 / 3.0 * M_PI - 3 * lens_volume(R, R, s)) / (s * s * s);
  EXPECT_NEAR(relative_density(test::lattice("simple_cubic", 4, s, R)), expect, 1e-12);
}

TEST(BondNetwork, RatioRuleOnSimpleCubicLattice) {
  Network net;
  net.packing = test::lattice("simple_cubic", 5, 2.0, 1.0);
  const BondingReport rep = test::bond_ratio(net, 0.2);
  EXPECT_EQ(rep.n_bonds, 3 * 125);
  EXPECT_NEAR(rep.bonds_per_particle, 6.0, 1e-12);
  for (double a : net.packing.bonds.radius) EXPECT_NEAR(a, 0.2, 1e-12);
  for (double l : net.packing.bonds.rest_length) EXPECT_NEAR(l, 2.0, 1e-12);
  EXPECT_EQ(rep.clusters.size.size(), 1u);
  EXPECT_EQ(rep.clusters.wrap_rank[rep.clusters.main], 3);
  // Images: bonds across a face carry the image of the neighbour.
  long across = 0;
  for (const Image& im : net.image) across += (im[0] != 0) + (im[1] != 0) + (im[2] != 0);
  EXPECT_EQ(across, 3 * 25);
}

TEST(BondNetwork, OverlapRuleGivesIntersectionCircleAndGapToleranceFloor) {
  Network net;
  net.packing = test::lattice("simple_cubic", 4, 1.9, 1.0);
  BondingOptions o;
  o.rule = NeckRule::overlap;
  bond_network(net, o);
  ASSERT_EQ(net.packing.bonds.size(), 3u * 64);
  EXPECT_NEAR(net.packing.bonds.radius[0], std::sqrt(1 - 0.95 * 0.95), 1e-12);
  // Spacing 2.05 R: gap 0.05 R; bonded only with the tolerance, at the floor ratio.
  Network gap;
  gap.packing = test::lattice("simple_cubic", 4, 2.05, 1.0);
  o.gap_tolerance = 0.04;
  EXPECT_EQ(bond_network(gap, o).n_bonds, 0);
  o.gap_tolerance = 0.06;
  o.min_neck_ratio = 0.03;
  EXPECT_EQ(bond_network(gap, o).n_bonds, 3 * 64);
  EXPECT_NEAR(gap.packing.bonds.radius[0], 0.03, 1e-12);
}

TEST(BondNetwork, DensityRuleReachesTarget) {
  Network net = test::random_network(400, 1.0, 0.3, 0.55, 11);
  EXPECT_NEAR(relative_density(net.packing), 0.55, 1e-6);
  EXPECT_GT(net.packing.bonds.size(), 400u);
}

TEST(BondNetwork, ExcludedPhasePairGetsNoBonds) {
  // Checkerboard SC lattice: every bond joins phases 0 and 1; excluding (0, 1) leaves none,
  // excluding (0, 0) leaves all.
  Network net;
  net.packing = test::lattice("simple_cubic", 4, 2.0, 1.0);
  net.packing.materials.push_back(test::ceramic());
  for (std::size_t k = 0; k < net.packing.particles.size(); ++k) {
    const Vec3 x = net.packing.particles.position[k];
    net.packing.particles.phase[k] = int(std::floor(x.x / 2) + std::floor(x.y / 2) + std::floor(x.z / 2)) % 2;
  }
  BondingOptions o;
  o.rule = NeckRule::ratio;
  o.gap_tolerance = 1e-6;
  o.excluded = {{0, 0}};
  EXPECT_EQ(bond_network(net, o).n_bonds, 3 * 64);
  o.excluded = {{1, 0}};
  EXPECT_EQ(bond_network(net, o).n_bonds, 0);
}

TEST(Clusters, SlabWrapsInTwoDirectionsAndRattlersAreIsolated) {
  Network net;
  net.packing = test::lattice("simple_cubic", 4, 2.0, 1.0);
  test::bond_ratio(net, 0.1);
  // Remove the bonds along z: four x–y planes, each wrapping in two directions.
  Packing& p = net.packing;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const Vec3 d = bond_vector(p, net.image[b], b);
    if (std::abs(d.z) > 1) p.bonds.state[b] = BondTable::broken;
  }
  Clusters c = find_clusters(p, net.image);
  EXPECT_EQ(c.size.size(), 4u);
  for (int r : c.wrap_rank) EXPECT_EQ(r, 2);
  EXPECT_EQ(c.spanning_clusters, 0);
  // Restore, then isolate one particle: a rattler outside the main cluster.
  for (auto& s : p.bonds.state) s = BondTable::intact;
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    if (p.bonds.i[b] == 5 || p.bonds.j[b] == 5) p.bonds.state[b] = BondTable::broken;
  c = find_clusters(p, net.image);
  EXPECT_EQ(c.isolated, 1);
  EXPECT_EQ(c.outside_main, 1);
  EXPECT_EQ(c.wrap_rank[c.main], 3);
}
