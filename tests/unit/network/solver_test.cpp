// The Kirchhoff solver against closed forms: series resistors, and a source term.
#include <gtest/gtest.h>

#include <cmath>

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
  EXPECT_THROW(parse_preconditioner("amg"), std::exception);
}
