// The Kirchhoff solver against closed forms: series resistors, and a source term.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "tomodem/network/solver.hpp"

using namespace tomodem::network;

namespace {
// Chain 0 - 1 - ... - (n-1) with conductances g_k; ends fixed at 1 V and 0 V.
void check_chain(Preconditioner pc) {
  const int n = 50;
  Graph g;
  g.n_nodes = n;
  double rsum = 0;
  for (int k = 0; k + 1 < n; ++k) {
    const double gk = 1.0 + (k % 7) * 1e3;  // contrast 7e3 along the chain
    g.add_edge(k, k + 1, gk);
    rsum += 1.0 / gk;
  }
  std::vector<uint8_t> active(n, 1), fixed(n, 0);
  fixed[0] = fixed[n - 1] = 1;
  std::vector<double> v(n, 0.0);
  v[0] = 1.0;
  SolverOptions o;
  o.tolerance = 1e-13;
  o.preconditioner = pc;
  const SolverReport r = solve_kirchhoff(g, active, fixed, {}, v, o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.unknowns, static_cast<std::size_t>(n - 2));
  // Series: the current through every edge is 1 V / Σ 1/g (round-off only: 1e-10 relative).
  const double I = 1.0 / rsum;
  for (int k = 0; k + 1 < n; ++k) EXPECT_NEAR(g.g[k] * (v[k] - v[k + 1]), I, 1e-10 * I) << "edge " << k;
}
}  // namespace

TEST(Solver, SeriesChainIncompleteCholesky) { check_chain(Preconditioner::incomplete_cholesky); }
TEST(Solver, SeriesChainJacobi) { check_chain(Preconditioner::jacobi); }
TEST(Solver, SeriesChainMultigrid) { check_chain(Preconditioner::amg); }

// A 3-D grid of 40³ nodes (six neighbours) with conductances log-uniform over three decades, the
// x faces at 1 V and 0 V. Multigrid (several levels at this size) and incomplete Cholesky solve
// to a relative residual of 1e-12; the potentials then agree within κ·1e-12 ≲ 1e-6 V (κ ≈ contrast
// × n² ≈ 2e6), and multigrid needs far fewer iterations (IC's count grows like n, multigrid's
// hardly at all).
TEST(Solver, MultigridAgreesWithIncompleteCholeskyOnRandomGrid) {
  const int n = 40;
  Graph g;
  g.n_nodes = n * n * n;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 3);
  auto id = [&](int x, int y, int z) { return x + n * (y + n * z); };
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        if (x + 1 < n) g.add_edge(id(x, y, z), id(x + 1, y, z), std::pow(10.0, u(rng)));
        if (y + 1 < n) g.add_edge(id(x, y, z), id(x, y + 1, z), std::pow(10.0, u(rng)));
        if (z + 1 < n) g.add_edge(id(x, y, z), id(x, y, z + 1), std::pow(10.0, u(rng)));
      }
  std::vector<uint8_t> active(g.n_nodes, 1), fixed(g.n_nodes, 0);
  std::vector<double> v0(g.n_nodes, 0.0);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y) {
      fixed[id(0, y, z)] = fixed[id(n - 1, y, z)] = 1;
      v0[id(0, y, z)] = 1.0;
    }
  SolverOptions o;
  o.tolerance = 1e-12;
  std::vector<double> va = v0, vi = v0;
  o.preconditioner = Preconditioner::amg;
  const SolverReport ra = solve_kirchhoff(g, active, fixed, {}, va, o);
  o.preconditioner = Preconditioner::incomplete_cholesky;
  const SolverReport ri = solve_kirchhoff(g, active, fixed, {}, vi, o);
  std::printf("40^3 grid: multigrid %d iterations (%d levels, operator complexity %.2f), IC %d iterations\n",
              ra.iterations, ra.levels, ra.operator_complexity, ri.iterations);
  EXPECT_TRUE(ra.converged);
  EXPECT_LE(ra.residual, 1e-11);
  EXPECT_GE(ra.levels, 2);
  double worst = 0;
  for (std::size_t k = 0; k < va.size(); ++k) worst = std::max(worst, std::abs(va[k] - vi[k]));
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(2 * ra.iterations, ri.iterations);
  EXPECT_LT(ra.operator_complexity, 2.0);  // coarse levels cost less than the finest one
}

TEST(Solver, InactiveNodesAndEdgesAreIgnored) {
  Graph g;
  g.n_nodes = 4;
  g.add_edge(0, 1, 1);
  g.add_edge(1, 2, 1);
  g.add_edge(1, 3, 5);  // node 3 inactive: its edge must not load node 1
  std::vector<uint8_t> active = {1, 1, 1, 0}, fixed = {1, 0, 1, 0};
  std::vector<double> v = {2.0, 0.0, 0.0, 123.0};
  const SolverReport r = solve_kirchhoff(g, active, fixed, {}, v, SolverOptions{});
  EXPECT_NEAR(v[1], 1.0, 1e-12);
  EXPECT_EQ(v[3], 123.0);
  EXPECT_EQ(r.unknowns, 1u);
}

TEST(Solver, SourceTermGivesOhmicRise) {
  // One free node tied to ground through g = 4 S with 2 A injected: v = 0.5 V.
  Graph g;
  g.n_nodes = 2;
  g.add_edge(0, 1, 4.0);
  std::vector<uint8_t> active = {1, 1}, fixed = {1, 0};
  std::vector<double> v = {0.0, 0.0}, src = {0.0, 2.0};
  solve_kirchhoff(g, active, fixed, src, v, SolverOptions{});
  EXPECT_NEAR(v[1], 0.5, 1e-14);
}

TEST(Solver, PreconditionerNames) {
  EXPECT_EQ(parse_preconditioner("ic"), Preconditioner::incomplete_cholesky);
  EXPECT_EQ(parse_preconditioner("jacobi"), Preconditioner::jacobi);
  EXPECT_EQ(parse_preconditioner("amg"), Preconditioner::amg);
  EXPECT_THROW(parse_preconditioner("hypre"), std::exception);
}
