// Bond percolation on the simple cubic lattice (docs/physics.md#percolation): threshold p_c = 0.2488 and the
// conductivity exponent t ≈ 2.0, σ ∝ (p − p_c)^t. Small lattices and few replicas keep it fast;
// the tolerances below come from the statistics of those choices.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lattice.hpp"
#include "tomodem/network/conductivity.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {
// L×L×L bond-diluted lattice as a graph, electrodes on the x = 0 and x = L−1 planes.
double spanning_probability(int L, double p, int replicas, unsigned seed) {
  int spans = 0;
  for (int r = 0; r < replicas; ++r) {
    std::mt19937_64 rng(seed + 7919u * r + 104729u * L);
    std::bernoulli_distribution keep(p);
    Graph g;
    g.n_nodes = static_cast<std::size_t>(L) * L * L;
    std::vector<int8_t> term(g.n_nodes, -1);
    auto id = [L](int x, int y, int z) { return (x * L + y) * L + z; };
    for (int x = 0; x < L; ++x)
      for (int y = 0; y < L; ++y)
        for (int z = 0; z < L; ++z) {
          if (x == 0) term[id(x, y, z)] = 0;
          if (x == L - 1) term[id(x, y, z)] = 1;
          if (x + 1 < L && keep(rng)) g.add_edge(id(x, y, z), id(x + 1, y, z), 1.0);
          if (y + 1 < L && keep(rng)) g.add_edge(id(x, y, z), id(x, y + 1, z), 1.0);
          if (z + 1 < L && keep(rng)) g.add_edge(id(x, y, z), id(x, y, z + 1), 1.0);
        }
    // All conductances are positive, so σ > 0 exactly when a cluster joins the two electrodes:
    // the spanning test that gates every solve is where the conductivity vanishes.
    const auto span = spanning_nodes(g, term);
    for (auto s : span)
      if (s) { ++spans; break; }
  }
  return static_cast<double>(spans) / replicas;
}
}  // namespace

// The threshold where the conductivity vanishes: the spanning probabilities of two lattice sizes
// cross at p_c up to a shift of order L^(−1/ν−ω), small next to the ±0.01 criterion. With 200
// replicas the binomial noise of each probability is ≤ 0.035; the curves' slopes differ by ≈ 15
// per unit p at p_c, so the crossing moves by ≈ 0.003 (1σ).
TEST(Percolation, BondDilutedCubicThresholdFromConductivityVanishing) {
  const int n = 7, replicas = 200;
  double prev_diff = 0, prev_p = 0, crossing = -1;
  for (int k = 0; k < n; ++k) {
    const double p = 0.235 + 0.005 * k;
    const double diff = spanning_probability(20, p, replicas, 11) - spanning_probability(10, p, replicas, 13);
    if (k > 0 && prev_diff < 0 && diff >= 0) crossing = prev_p + (p - prev_p) * (-prev_diff) / (diff - prev_diff);
    prev_diff = diff;
    prev_p = p;
  }
  std::printf("spanning probabilities of L = 10 and 20 cross at p = %.4f\n", crossing);
  ASSERT_GT(crossing, 0) << "no crossing of the spanning probabilities in [0.235, 0.265]";
  EXPECT_NEAR(crossing, 0.249, 0.01);
}

// Conductivity exponent: σ(p) on L = 32 lattices (bonds of a Packing, through the full network
// path) fitted as log σ = log A + t log(p − p_c) with p_c = 0.2488, for p in [0.28, 0.34]: there
// the correlation length (≈ |p − p_c|^−0.88 ≲ 20) stays below L and the window is close enough to
// p_c for the power law. Finite size and corrections to scaling make the effective exponent of
// such a window fall below the asymptotic 2.0 (we measure 1.82); we accept 1.6 < t < 2.3.
TEST(Percolation, BondDilutedCubicConductivityExponent) {
  const int L = 32, replicas = 3;
  const double pc = 0.2488;
  std::vector<double> xs, ys;
  for (double p : {0.28, 0.30, 0.32, 0.34}) {
    double mean = 0;
    for (int r = 0; r < replicas; ++r) {
      std::mt19937_64 rng(1000u * r + 7u);
      std::bernoulli_distribution keep(p);
      const Packing pk = test::sc_lattice(L, L, L, 0.5, 0.1, false, nullptr, [&] { return keep(rng); });
      NetworkOptions no;
      no.use_contacts = false;
      // The lattice's Laguerre faces are unit squares, whose cap lies far above Holm's 2σa = 0.2:
      // it never binds here, and its tessellation was 2/3 of the test's time.
      no.face_cap = false;
      const Network net = build_network(pk, no);
      ConductOptions co;
      co.solver.tolerance = 1e-8;  // σ to ~1e-8: far below the replica scatter (~5 %)
      co.keep_fields = false;
      const AxisResult a = solve_electrodes(net, 0, co);
      EXPECT_TRUE(a.percolates);
      EXPECT_LT(a.conservation_error, 1e-5);
      mean += a.sigma_eff / replicas;
    }
    const double G = 2 * 0.1;  // σ of the intact lattice is G/(2R) = G with R = 0.5
    xs.push_back(std::log(p - pc));
    ys.push_back(std::log(mean / G));
  }
  const double n = static_cast<double>(xs.size());
  double mx = 0, my = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) { mx += xs[k] / n; my += ys[k] / n; }
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    sxy += (xs[k] - mx) * (ys[k] - my);
    sxx += (xs[k] - mx) * (xs[k] - mx);
  }
  const double t = sxy / sxx;
  RecordProperty("exponent", std::to_string(t));
  std::printf("conductivity exponent t = %.3f\n", t);
  EXPECT_GT(t, 1.6);
  EXPECT_LT(t, 2.3);
}
