// Electrodes on a periodic cell (docs/conduct.md#boundary-conditions) against the periodic tensor
// (issue 18 item 7: the electrodes read 3-5 % above the periodic solve on sintered samples).
// The plates cut the branches that cross the cell's faces; each node keeps the share of its
// edge's resistance on its side of the plane. Two independent references:
//  (1) a Bravais lattice (SC, BCC, FCC) with equal edges carries the affine potential exactly,
//      whatever its position in the cell: σ_el = σ_xx = (1/V) Σ_e g_e b_x² (hand sum), also with
//      sites on the faces and at offsets where no particle touches a face within the tolerance;
//  (2) a disordered network: the plates pin the potential fluctuation at the points where the
//      cut plane crosses branches, which the periodic solve leaves free, so σ_el ≥ σ_xx
//      (a minimum of the dissipation over fewer fields: Dirichlet's principle; Hazanov & Huet,
//      J. Mech. Phys. Solids 42, 1995, 1994), and the excess is a boundary layer: it falls like 1/L.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/network.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {

enum class Bravais { sc, bcc, fcc };

/// A sphere of the conducting phase at r wrapped into the periodic cube [0, L)³.
void add_site(Packing& p, Vec3 r, double radius, double L) {
  for (int k = 0; k < 3; ++k) r[k] -= L * std::floor(r[k] / L);
  p.particles.position.push_back(r);
  p.particles.radius.push_back(radius);
  p.particles.phase.push_back(0);
}

/// The periodic cube of edge L and one material of conductivity 1.
Packing periodic_cube(Packing& p, double L) {
  p.cell = Cell::box({0, 0, 0}, {L, L, L}, true);
  Material m;
  m.name = "solid";
  m.conductivity = 1.0;
  p.materials = {m};
  return p;
}

/// n³ cubic cells of edge c, sites shifted by `offset`, spheres overlapping their nearest neighbours
/// (radius 0.6 × the nearest-neighbour distance), periodic, σ = 1.
Packing bravais(Bravais kind, int n, double c, const Vec3& offset) {
  std::vector<Vec3> basis = {{0, 0, 0}};
  double nn = c;
  if (kind == Bravais::bcc) {
    basis.push_back({0.5, 0.5, 0.5});
    nn = std::sqrt(3.0) / 2 * c;
  } else if (kind == Bravais::fcc) {
    basis.insert(basis.end(), {{0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}});
    nn = c / std::sqrt(2.0);
  }
  Packing p;
  const double L = n * c;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z)
        for (const Vec3& b : basis) {
          add_site(p, (Vec3(x, y, z) + b) * c + offset, 0.6 * nn, L);
        }
  return periodic_cube(p, L);
}

/// n³ sites of a simple cubic grid of spacing d, each moved by a uniform jitter of ±0.3 d per
/// coordinate, radius 0.62 d: a connected, disordered, statistically homogeneous network.
Packing jittered(int n, double d, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jit(-0.3 * d, 0.3 * d);
  Packing p;
  const double L = n * d;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) {
        add_site(p, Vec3((x + 0.5) * d + jit(rng), (y + 0.5) * d + jit(rng), (z + 0.5) * d + jit(rng)), 0.62 * d, L);
      }
  return periodic_cube(p, L);
}

ConductOptions tight() {
  ConductOptions o;
  o.solver.tolerance = 1e-13;
  return o;
}

}  // namespace

// (1) Lattices: electrodes = periodic = hand sum, on every axis and at every offset. Sites on
// the faces (offset 0: FCC's layer at x = 0 is both faces' particle), a quarter cell in, and a
// generic offset where the old selection (surface within 0.05 r of a face, L between the mean
// centre planes) found no particle at the high face. 1e-9: the solves run to 1e-13.
TEST(ElectrodePlates, LatticesMatchThePeriodicTensorExactly) {
  const double c = 1e-5;
  for (Bravais kind : {Bravais::sc, Bravais::bcc, Bravais::fcc})
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(0.25 * c, 0.25 * c, 0.25 * c), Vec3(0.1 * c, 0.37 * c, 0.13 * c)}) {
      const Network net = build_network(bravais(kind, 3, c, offset), NetworkOptions{});
      ASSERT_GT(net.n_edges(), 0u);
      const TensorResult per = solve_periodic(net, tight());
      for (int k = 0; k < 3; ++k) {
        double hand = 0;
        for (std::size_t e = 0; e < net.n_edges(); ++e) hand += net.graph.g[e] * std::pow(net.branch(e)[k], 2);
        hand /= net.cell.volume();
        const AxisResult el = solve_electrodes(net, k, tight());
        const std::string what = "lattice " + std::to_string(int(kind)) + " offset " + std::to_string(offset[1] / c) +
                                 " axis " + std::to_string(k);
        ASSERT_TRUE(el.percolates) << what;
        EXPECT_NEAR(per.sigma[k][k], hand, 1e-9 * hand) << what;
        EXPECT_NEAR(el.sigma_eff, hand, 1e-9 * hand) << what;
        EXPECT_NEAR(el.length, 3 * c, 1e-12 * c) << what;  // the cell: the plates are its faces
        EXPECT_LT(el.conservation_error, 1e-9) << what;
      }
    }
}

// (2) Disordered networks of n = 4, 6, 8, 12 sites per edge (4 seeds each, three axes): the
// electrodes never read below the periodic tensor (Dirichlet's principle; 1e-9 for the solves),
// and the excess is a boundary layer: measured +1.39, +0.96, +0.66, +0.45 %, n × excess
// 0.056, 0.057, 0.053, 0.054; asserted within a factor 1.5 of n = 4's (12 samples per size
// scatter by about 10 %) while the excess itself falls 3-fold. The old electrodes (whole
// particles at depths 0 … 1.05 r held at the plate potential, L between their mean centre
// planes) read +2.7, +2.1, +1.1, +0.7 %, and 13 of the 48 samples below the periodic value.
TEST(ElectrodePlates, DisorderedNetworksReadAtLeastThePeriodicValueWithAOneOverLExcess) {
  const double d = 1e-5;
  const int sizes[] = {4, 6, 8, 12};
  std::vector<double> mean_excess;
  for (int n : sizes) {
    double sum = 0;
    int count = 0;
    for (unsigned seed = 1; seed <= 4; ++seed) {
      const Network net = build_network(jittered(n, d, 1000 * n + seed), NetworkOptions{});
      const TensorResult per = solve_periodic(net, tight());
      for (int k = 0; k < 3; ++k) {
        const AxisResult el = solve_electrodes(net, k, tight());
        ASSERT_TRUE(el.percolates);
        const double excess = el.sigma_eff / per.sigma[k][k] - 1;
        EXPECT_GT(excess, -1e-9) << "n " << n << " seed " << seed << " axis " << k;
        sum += excess;
        ++count;
      }
    }
    mean_excess.push_back(sum / count);
    std::printf("n = %2d: electrodes / periodic - 1 = %+.5f (mean of %d), n x excess = %.4f\n", n, sum / count,
                count, n * sum / count);
  }
  for (std::size_t s = 1; s < mean_excess.size(); ++s) {
    const double ratio = sizes[s] * mean_excess[s] / (sizes[0] * mean_excess[0]);
    EXPECT_GT(ratio, 1 / 1.5) << "n = " << sizes[s];
    EXPECT_LT(ratio, 1.5) << "n = " << sizes[s];
  }
  EXPECT_LT(mean_excess.back(), mean_excess.front() / 2);
}
