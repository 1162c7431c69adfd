// PETSc's CG + GAMG (tomodem/linalg/petsc_solver.hpp) against closed forms and the in-house
// solvers, on every rank count the test runs with (docs/solvers.md). The tools assemble only
// their rank's rows for PETSc (young, conduct, fracture below); every rank solves the serial
// references itself. The first PetscSolver tests hand PETSc the whole matrix or the rank's rows.
//
// Tolerances. A CG solution with relative residual ρ = |f − K q|/|f| has the error δq = K⁻¹r;
// a quantity that is a linear functional of q weighted by another right-hand side (a stress
// component f_iᵀq / V, a current through a face) then moves, relative to its fluctuating part
// fᵀK⁻¹f, by at most ρ √κ (Cauchy–Schwarz in the K⁻¹ inner product, |r| ≤ ρ|f|, and
// fᵀK⁻¹f ≥ |f|²/λ_max). κ = λ_max/λ_min: the random grid below has κ ≈ contrast × n² ≈ 1e3 ×
// 30² ≈ 1e6; the bonded networks (6 DOF per particle, rotations scaled by the mean radius, Z ≈ 5)
// stay below 1e8 (the in-house test LdltAndIterativeSolversAgree rests on the same bound).
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "../../validation/fracture/samples.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/linalg/petsc_solver.hpp"
#include "tomodem/mechanics/elastic.hpp"
#include "tomodem/network/solver.hpp"

using namespace tomodem;

namespace {

int world_size() {
  int n = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

bool rank0() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r == 0;
}

/// n × n × n grid, six neighbours, the x = 0 face at 1 V and x = n−1 at 0 V; conductances g
/// (uniform when `decades` is 0, else log-uniform over that many decades).
struct Grid {
  network::Graph g;
  std::vector<uint8_t> active, fixed;
  std::vector<double> v;
  int n = 0;
};
Grid grid(int n, double decades, unsigned seed) {
  Grid G;
  G.n = n;
  G.g.n_nodes = std::size_t(n) * n * n;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, decades);
  auto id = [&](int x, int y, int z) { return x + n * (y + n * z); };
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        if (x + 1 < n) G.g.add_edge(id(x, y, z), id(x + 1, y, z), std::pow(10.0, u(rng)));
        if (y + 1 < n) G.g.add_edge(id(x, y, z), id(x, y + 1, z), std::pow(10.0, u(rng)));
        if (z + 1 < n) G.g.add_edge(id(x, y, z), id(x, y, z + 1), std::pow(10.0, u(rng)));
      }
  G.active.assign(G.g.n_nodes, 1);
  G.fixed.assign(G.g.n_nodes, 0);
  G.v.assign(G.g.n_nodes, 0.0);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y) {
      G.fixed[std::size_t(id(0, y, z))] = G.fixed[std::size_t(id(n - 1, y, z))] = 1;
      G.v[std::size_t(id(0, y, z))] = 1.0;
    }
  return G;
}

/// Current out of the 1 V face after solving with `pc` to `tolerance`.
double face_current(Grid G, network::Preconditioner pc, double tolerance, network::SolverReport* report) {
  network::SolverOptions o;
  o.preconditioner = pc;
  o.tolerance = tolerance;
  *report = network::solve_kirchhoff(G.g, G.active, G.fixed, {}, G.v, o);
  double I = 0;
  for (std::size_t e = 0; e < G.g.n_edges(); ++e) {
    const int32_t a = G.g.i[e], b = G.g.j[e];
    if (G.v[std::size_t(a)] == 1.0 && G.fixed[std::size_t(a)] && !G.fixed[std::size_t(b)])
      I += G.g.g[e] * (1.0 - G.v[std::size_t(b)]);
  }
  return I;
}

}  // namespace

// A chain Laplacian straight through PetscSolver: the rows are split over every rank and the
// linear potential between the two fixed ends comes back whole on each of them.
TEST(PetscSolver, ChainSplitsRowsAndReturnsTheWholeSolution) {
  const int32_t n = 1000;  // unknowns 1..n between v_0 = 1 and v_{n+1} = 0
  std::vector<int32_t> start{0}, column;
  std::vector<double> value, b(std::size_t(n), 0.0), x(std::size_t(n), 0.0);
  for (int32_t i = 0; i < n; ++i) {
    if (i > 0) column.push_back(i - 1), value.push_back(-1);
    column.push_back(i), value.push_back(2);
    if (i + 1 < n) column.push_back(i + 1), value.push_back(-1);
    start.push_back(int32_t(column.size()));
  }
  b[0] = 1;
  PetscSolveOptions o;
  o.tolerance = 1e-12;
  const PetscSolver s(CsrView{n, start.data(), column.data(), value.data()}, NearNullspace{}, o);
  const PcgReport r = s.solve(b.data(), x.data());
  EXPECT_EQ(s.stats().ranks, world_size());
  EXPECT_TRUE(r.converged);
  EXPECT_LE(r.residual, 1e-12);
  // κ of the chain ≈ 4n²/π² ≈ 4e5: the potentials within κ ρ ≲ 1e-6 of the exact 1 − i/(n+1).
  for (int32_t i = 0; i < n; ++i) EXPECT_NEAR(x[std::size_t(i)], 1.0 - double(i + 1) / (n + 1), 1e-6) << i;
}

// Uniform conductance g = 1: n² parallel chains of n − 1 unit resistors, I = n² / (n − 1) exactly.
TEST(PetscConduct, UniformGridCurrentIsExact) {
  const int n = 24;
  network::SolverReport rep;
  const double I = face_current(grid(n, 0, 1), network::Preconditioner::petsc, 1e-12, &rep);
  EXPECT_TRUE(rep.converged);
  // κ ≈ 4 n²/π² · 3 ≈ 700: ρ √κ ≈ 3e-11; 1e-9 leaves room for round-off in the sum.
  EXPECT_NEAR(I / (double(n) * n / (n - 1)), 1.0, 1e-9);
}

// Three decades of random conductances on 30³ nodes: PETSc and the in-house multigrid give the
// same current (σ = I L / (A ΔV)) within ρ √κ ≈ 1e-12 · 1e3 = 1e-9 each; asserted at 1e-8.
TEST(PetscConduct, RandomGridAgreesWithInHouseMultigrid) {
  const Grid G = grid(30, 3, 11);
  network::SolverReport a, p;
  const double Ia = face_current(G, network::Preconditioner::amg, 1e-12, &a);
  const double Ip = face_current(G, network::Preconditioner::petsc, 1e-12, &p);
  if (rank0()) std::printf("conduct 30^3 on %d rank(s): in-house PCG+AMG %d iterations, PETSc CG+GAMG %d iterations (%d levels)\n",
              world_size(), a.iterations, p.iterations, p.levels);
  EXPECT_TRUE(p.converged);
  EXPECT_LE(p.residual, 1e-11);  // recomputed; CG stops on its recursive residual
  EXPECT_NEAR(Ip / Ia, 1.0, 1e-8);
}

// E, ν and every C_ij of a random bonded packing (800 particles, 4 800 DOF): PETSc at ρ = 1e-10
// against the exact LDLT, within ρ √κ ≤ 1e-10 · 1e4 = 1e-6 of C11.
TEST(PetscYoung, TensorAgreesWithLdlt) {
  using namespace tomodem::mechanics;
  const Network net = test::random_network(800, 0.5e-3, 0.30, 0.55, 9, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, false);
  const BondStiffnesses k = bond_stiffnesses(net.packing, laws);
  ImplicitOptions o;
  o.tolerance = 1e-10;
  o.solver = ElasticSolver::ldlt;
  const ImplicitResult ref = solve_implicit(net.packing, net.image, k, o);
  o.solver = ElasticSolver::petsc;
  const ImplicitResult r = solve_implicit(net.packing, net.image, k, o);
  if (rank0()) std::printf("young N=800 on %d rank(s): PETSc %ld iterations over 6 cases, %d levels, residual %.1e; E %.6e vs %.6e\n",
              world_size(), r.iterations, r.levels, r.residual, r.E, ref.E);
  EXPECT_EQ(r.solver, ElasticSolver::petsc);
  EXPECT_LE(r.residual, 1e-9);  // recomputed |K q − f|/|f|: the CG criterion plus round-off
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) EXPECT_NEAR(r.C[i][j], ref.C[i][j], 1e-6 * ref.C[0][0]) << i << j;
  EXPECT_NEAR(r.E / ref.E, 1.0, 1e-6);
  EXPECT_NEAR(r.nu, ref.nu, 1e-6);
  EXPECT_GT(r.iterations, 0);
}

// The sequentially linear analysis with PETSc (warm starts, GAMG interpolation kept between
// breaks) breaks the same bonds in the same order as LDLT: ρ = 1e-10 moves each bond's criterion
// ratio (linear in q) by ≲ ρ √κ ≤ 1e-6, and the closest pair of competing openings is checked to
// be further apart than that, so a swap would be a real disagreement.
TEST(PetscFracture, SlaBreaksTheSameBondsAsLdlt) {
  using namespace tomodem::mechanics;
  const Network net = test::slab(12, 3, 18, 21);
  FailureOptions f;
  const auto laws = test::lefm_laws(net.packing, f);
  CrackOptions c;
  c.a_over_w = 0.1875;
  const FractureSample s = make_sample(net, c);
  SlaOptions o;
  o.stop_fraction = 0.5;
  o.event_tolerance = 0;
  o.solver = SlaSolver::ldlt;
  const FractureResult a = run_sla(s, laws, f, o);
  o.solver = SlaSolver::petsc;
  o.cg_tolerance = 1e-10;
  const FractureResult b = run_sla(s, laws, f, o);
  if (rank0()) std::printf("SLA on %d rank(s): %zu events, K_IC %.6e (LDLT) %.6e (PETSc), %ld CG iterations in %ld solves, %ld rebuilds\n",
              world_size(), a.events.size(), a.K_IC, b.K_IC, b.cg_iterations, b.solves, b.amg_rebuilds);
  EXPECT_EQ(b.solver, SlaSolver::petsc);
  ASSERT_GT(a.events.size(), 10u);
  ASSERT_EQ(a.events.size(), b.events.size());
  double closest = HUGE_VAL;
  for (std::size_t e = 0; e < a.events.size(); ++e) {
    EXPECT_EQ(a.events[e].bond, b.events[e].bond) << "event " << e;
    EXPECT_NEAR(b.events[e].displacement / a.events[e].displacement, 1.0, 1e-6) << "event " << e;
    if (e > 0) closest = std::min(closest, std::abs(a.events[e].displacement / a.events[e - 1].displacement - 1));
  }
  EXPECT_GT(closest, 1e-6);
  EXPECT_NEAR(b.K_IC / a.K_IC, 1.0, 1e-6);
  // Warm starts: after the first (cold) solve the others need fewer iterations on average.
  EXPECT_LT(double(b.cg_iterations - b.cg_iterations_fresh) / double(std::max(1L, b.solves - 1)),
            double(b.cg_iterations_fresh));
}

namespace {
/// Rows [first, last) of a chain of springs along x with three unknowns per node (block size 3):
/// node i couples to i ± 1 with stiffness 1 + (i mod 7) in every component (a diagonal 3×3 block),
/// and a ground spring of 0.1 at every node (so the system is regular without pinning). Columns
/// are whole-system unknowns; start begins at 0.
struct Rows {
  std::vector<int32_t> start{0}, column;
  std::vector<double> value;
};
Rows chain3(int32_t nodes, int32_t first_node, int32_t last_node) {
  Rows r;
  auto k = [](int32_t i) { return 1.0 + double(i % 7); };  // spring between nodes i and i + 1
  for (int32_t i = first_node; i < last_node; ++i)
    for (int c = 0; c < 3; ++c) {
      if (i > 0) r.column.push_back(3 * (i - 1) + c), r.value.push_back(-k(i - 1));
      r.column.push_back(3 * i + c), r.value.push_back(0.1 + (i > 0 ? k(i - 1) : 0) + (i + 1 < nodes ? k(i) : 0));
      if (i + 1 < nodes) r.column.push_back(3 * (i + 1) + c), r.value.push_back(-k(i));
      r.start.push_back(int32_t(r.column.size()));
    }
  return r;
}
NearNullspace chain3_ns(int32_t nodes) {
  NearNullspace ns;
  for (int32_t i = 0; i < nodes; ++i) {
    for (int c = 0; c < 3; ++c) ns.node.push_back(i), ns.kind.push_back(int8_t(c));
    ns.position.push_back(Vec3{double(i), 0, 0});
  }
  ns.rotation_scale = 1;
  return ns;
}
}  // namespace

// Distributed assembly (PetscRows): each rank builds only the rows of the nodes owned_nodes gives
// it (701 nodes: the split is uneven on 2 and 3 ranks) and hands PETSc its part of b; the whole
// solution comes back on every rank and equals the solve of the whole matrix on every rank, and
// both satisfy the whole system. Solved to 1e-13: the two runs differ only in round-off of the
// assembly order, so they agree to κρ ≲ 1e4 · 1e-13 (κ ≈ 8 max k / 0.1 ground ≈ 6e2 ... 1e4).
TEST(PetscSolver, LocalRowsGiveTheWholeMatrixSolution) {
  const int32_t nodes = 701, n = 3 * nodes;
  const NearNullspace ns = chain3_ns(nodes);
  std::vector<double> b(static_cast<std::size_t>(n));
  for (int32_t u = 0; u < n; ++u) b[std::size_t(u)] = std::sin(0.37 * u) + (u % 3 == 1 ? 0.5 : 0.0);
  PetscSolveOptions o;
  o.tolerance = 1e-13;
  const Rows whole = chain3(nodes, 0, nodes);
  std::vector<double> x_whole(std::size_t(n), 0.0), x_local(std::size_t(n), 0.0);
  const PetscSolver sw(CsrView{n, whole.start.data(), whole.column.data(), whole.value.data()}, ns, o);
  ASSERT_TRUE(sw.solve(b.data(), x_whole.data()).converged);

  const auto [n0, n1] = PetscSolver::owned_nodes(nodes);
  EXPECT_LE(std::abs((n1 - n0) - nodes / world_size()), 1) << "balanced split";
  const Rows mine = chain3(nodes, n0, n1);
  const int32_t first = 3 * n0, count = 3 * (n1 - n0);
  const PetscSolver sl(CsrView{count, mine.start.data(), mine.column.data(), mine.value.data()}, PetscRows{n, first}, ns, o);
  const PcgReport r = sl.solve(b.data() + first, x_local.data());
  EXPECT_TRUE(r.converged);
  EXPECT_LE(r.residual, 1e-13);
  EXPECT_EQ(sl.stats().ranks, world_size());
  EXPECT_EQ(sl.stats().block_size, 3);
  EXPECT_EQ(sl.stats().nonzeros, sw.stats().nonzeros);  // 3 (3·nodes − 2) · 3 / 3: the same matrix
  double worst = 0, resid = 0, bnorm = 0;
  for (int32_t u = 0; u < n; ++u) {
    worst = std::max(worst, std::abs(x_local[std::size_t(u)] - x_whole[std::size_t(u)]));
    double Ax = 0;
    for (int32_t k = whole.start[std::size_t(u)]; k < whole.start[std::size_t(u) + 1]; ++k)
      Ax += whole.value[std::size_t(k)] * x_local[std::size_t(whole.column[std::size_t(k)])];
    resid += (b[std::size_t(u)] - Ax) * (b[std::size_t(u)] - Ax);
    bnorm += b[std::size_t(u)] * b[std::size_t(u)];
  }
  EXPECT_LE(worst, 1e-8);
  EXPECT_LE(std::sqrt(resid / bnorm), 1e-12);  // the whole system, checked here, not by PETSc

  // A new set of values on the same local pattern keeps the solver (replace_matrix), doubling K
  // halves x.
  Rows twice = mine;
  for (double& v : twice.value) v *= 2;
  std::vector<double> x2(std::size_t(n), 0.0);
  PetscSolver s2(CsrView{count, mine.start.data(), mine.column.data(), mine.value.data()}, PetscRows{n, first}, ns, o);
  s2.replace_matrix(CsrView{count, twice.start.data(), twice.column.data(), twice.value.data()});
  ASSERT_TRUE(s2.solve(b.data() + first, x2.data()).converged);
  for (int32_t u = 0; u < n; u += 97) EXPECT_NEAR(x2[std::size_t(u)], 0.5 * x_whole[std::size_t(u)], 1e-8) << u;
}

// Rows that are not the rank's own (shifted by one node) are refused on every rank at once, with
// a message, instead of a wrong matrix or a hang in the collective calls that follow.
TEST(PetscSolver, LocalRowsOfAnotherRankAreRefused) {
  const int32_t nodes = 50, n = 3 * nodes;
  const auto [n0, n1] = PetscSolver::owned_nodes(nodes);
  const int32_t a = n0 + 1, c = std::min(n1 + 1, nodes);
  const Rows wrong = chain3(nodes, a, c);
  EXPECT_THROW(PetscSolver(CsrView{3 * (c - a), wrong.start.data(), wrong.column.data(), wrong.value.data()},
                           PetscRows{n, 3 * a}, chain3_ns(nodes)),
               RuntimeFailure);
}
