// --solver auto: the cost model's choice, and the operation counts of the paths on reference
// networks ordered as the model predicts (issue 19). Counts and ratios only, and CPU-time ratios
// measured in this process: no wall times.
#include <gtest/gtest.h>

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "../../validation/mechanics/networks.hpp"
#include "tomodem/mechanics/elastic.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

namespace {
struct Net {
  Network net;
  std::vector<dem::BondLaw> laws;
};
Net random_net(int n, double density) {
  Net r{test::random_network(n, 0.5e-3, 0.30, density, 11, 0.05), {}};
  r.laws = bond_laws(r.net.packing, "", LawOptions{}, false);
  return r;
}
ImplicitResult run(const Net& n, ElasticSolver s, bool solve) {
  ImplicitOptions o;
  o.solver = s;
  o.tolerance = 1e-10;
  const BondStiffnesses k = bond_stiffnesses(n.net.packing, n.laws);
  if (solve) return solve_implicit(n.net.packing, n.net.image, k, o);
  const StiffnessSystem sys(n.net.packing, n.net.image, k, o);
  return sys.summary();
}
double seconds_of(const SolverCosts& c, ElasticSolver s) {
  return s == ElasticSolver::ldlt ? c.ldlt_s : s == ElasticSolver::amg ? c.amg_s : c.cg_s;
}
}  // namespace

// auto resolves to the path of least predicted cost, never one predicted > 2× another's, on
// networks from small and sparse to larger and denser.
TEST(SolverChoice, AutoNeverPicksAPathPredictedTwiceAnother) {
  for (const auto& [n, rho] : std::vector<std::pair<int, double>>{{100, 0.55}, {600, 0.55}, {1500, 0.55}, {300, 0.75},
                                                                 {1500, 0.75}}) {
    const ImplicitResult r = run(random_net(n, rho), ElasticSolver::automatic, false);
    const SolverCosts& c = r.predicted;
    const double best = std::min({c.ldlt_s, c.amg_s, c.cg_s});
    std::printf("N %d rho %.2f: predicted ldlt %.3g s (flops %.3g%s), amg %.3g s, cg %.3g s -> %s\n", n, rho, c.ldlt_s,
                c.factor_flops, c.factor_truncated ? ", truncated" : "", c.amg_s, c.cg_s, to_string(r.solver));
    EXPECT_NE(r.solver, ElasticSolver::automatic);
    // The cheapest prediction, or cg where auto's Jacobi-CG trial converged within its budget.
    EXPECT_TRUE(r.solver == c.cheapest || r.solver == ElasticSolver::cg) << to_string(r.solver);
    EXPECT_LE(seconds_of(c, r.solver), 2 * best);
    EXPECT_GT(best, 0);
  }
}

// Reference points where the model predicts a clear winner (> 2×): a small sparse network (ldlt)
// and a dense one of 1 500 particles (the multigrid; the case of the issue: Z ≈ 6, 1 975
// particles, LDLT 17× slower). The measured counts — flops and nonzeros of the factor Eigen
// computed, multigrid iterations × nonzeros of K — converted by the same constants, order the
// two paths the same way; the symbolic count of L is within 3× of the factor's (it counts on the
// particle graph, Eigen orders the 6× larger matrix: the orders differ a little), or, where it
// stopped early because LDLT was already 8× dearer, a lower bound of the factor's flops.
TEST(SolverChoice, MeasuredCountsOrderThePathsAsPredicted) {
  for (const auto& [n, rho] : std::vector<std::pair<int, double>>{{150, 0.55}, {1500, 0.75}}) {
    const Net net = random_net(n, rho);
    const ImplicitResult l = run(net, ElasticSolver::ldlt, true), a = run(net, ElasticSolver::amg, true);
    const SolverCosts& pred = l.predicted;
    SolverCosts measured = pred;
    measured.factor_flops = l.factor_flops;
    measured.factor_nonzeros = l.factor_nonzeros;
    measured.amg_iterations = double(a.iterations) / 6;
    measured = solver_costs_from_counts(measured, 6);
    std::printf("N %d rho %.2f: L nonzeros %.3g (predicted %.3g), flops %.3g (predicted %.3g); amg %.1f it/case "
                "(predicted %.1f); seconds ldlt %.3g / amg %.3g measured counts, %.3g / %.3g predicted\n",
                n, rho, l.factor_nonzeros, pred.factor_nonzeros, l.factor_flops, pred.factor_flops,
                measured.amg_iterations, pred.amg_iterations, measured.ldlt_s, measured.amg_s, pred.ldlt_s, pred.amg_s);
    const double predicted_ratio = pred.ldlt_s / pred.amg_s, measured_ratio = measured.ldlt_s / measured.amg_s;
    ASSERT_TRUE(predicted_ratio > 2 || predicted_ratio < 0.5) << "not a reference point: ratio " << predicted_ratio;
    EXPECT_EQ(predicted_ratio > 1, measured_ratio > 1);
    if (pred.factor_truncated) {
      // The count stopped once LDLT cost 8× the multigrid: what it counted is a lower bound.
      EXPECT_GE(l.factor_flops, pred.factor_flops);
      EXPECT_GT(measured_ratio, 8);
    } else {
      EXPECT_LT(std::max(l.factor_nonzeros / pred.factor_nonzeros, pred.factor_nonzeros / l.factor_nonzeros), 3.0);
    }
    EXPECT_NEAR(l.E / a.E, 1.0, 1e-8);  // same answer: the choice is about cost only
  }
}

namespace {
/// CPU seconds of this process (all threads) spent in f: the paths run one after another here, so
/// their ratio does not depend on what else the machine runs, unlike wall time.
template <class F>
double cpu_seconds(F&& f) {
  timespec a{}, b{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  f();
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  return double(b.tv_sec - a.tv_sec) + 1e-9 * double(b.tv_nsec - a.tv_nsec);
}
}  // namespace

// The demand: auto never takes a path 2× slower than another it offers (ldlt, amg, cg).
// On a perfect SC lattice the model (fitted on disordered networks) predicts amg, but Jacobi CG
// converges there in a fraction of the predicted iterations and was 4.1× faster (docs/young.md):
// auto's Jacobi-CG trial on the first strain case finds it and keeps CG. On a random network the
// trial does not converge within its budget (1/6 of the chosen path's predicted time) and auto
// pays it on top. Measured as CPU time of each path in this process, six cases to 1e-10; auto
// timed twice and the faster kept (CPU time is steady, but a shared cache still adds noise of
// order 10 %, small against the factor 2 asserted). Same E from every path to 1e-8 (the CG error
// bound ρ√κ of docs/solvers.md with ρ = 1e-10).
TEST(SolverChoice, AutoIsWithinTwiceTheFastestPathByCpuTime) {
  struct Case {
    const char* name;
    Net net;
  };
  std::vector<Case> cases;
  {
    Net sc;
    sc.net.packing = test::lattice("simple_cubic", 10, 1e-3, 0.5e-3);
    test::bond_ratio(sc.net, 0.1);
    sc.laws = bond_laws(sc.net.packing, "", LawOptions{}, false);
    cases.push_back({"SC lattice 10^3", std::move(sc)});
  }
  cases.push_back({"random N 1000 rho 0.75", random_net(1000, 0.75)});
  for (const Case& c : cases) {
    double best = HUGE_VAL, E_ref = 0;
    const char* best_name = "";
    for (ElasticSolver s : {ElasticSolver::ldlt, ElasticSolver::amg, ElasticSolver::cg}) {
      ImplicitResult r;
      const double t = cpu_seconds([&] { r = run(c.net, s, true); });
      std::printf("%s: %s %.3f s CPU, E %.9g\n", c.name, to_string(s), t, r.E);
      if (s == ElasticSolver::ldlt) E_ref = r.E;
      EXPECT_NEAR(r.E / E_ref, 1.0, 1e-8) << to_string(s);
      if (t < best) best = t, best_name = to_string(s);
    }
    ImplicitResult a;
    double t_auto = HUGE_VAL;
    for (int rep = 0; rep < 2; ++rep) t_auto = std::min(t_auto, cpu_seconds([&] { a = run(c.net, ElasticSolver::automatic, true); }));
    std::printf("%s: auto -> %s (model: %s) %.3f s CPU, fastest %s %.3f s: ratio %.2f\n", c.name, to_string(a.solver),
                to_string(a.predicted.cheapest), t_auto, best_name, best, t_auto / best);
    EXPECT_LE(t_auto, 2 * best) << c.name;
    EXPECT_NEAR(a.E / E_ref, 1.0, 1e-8);
  }
}

// The multigrid's iterations per strain case on SC lattices (a/R 0.1, periodic) of 8³ and 16³
// particles, 1e-10: an operation count, not a time. A multigrid whose hierarchy works needs
// nearly the same iterations at any size (measured: 10³ → 20³ → 30³ gives 53 → 66 → 75 per case;
// 8³ → 16³ here 43.3 → 59.3, ×1.37); Jacobi CG's iterations grow like √κ ∝ the lattice side, ×2 in
// theory (measured 64 → 116, ×1.81). The bound 1.5 lies between the two, and the test also checks
// that Jacobi CG does grow by > 1.5 on the same lattices, so the two sizes do tell the behaviours
// apart. Iteration counts are deterministic (serial below 50 000 unknowns). (The random network of Z 3.7
// does not pass this: docs/young.md, "Solvers".)
TEST(AmgScaling, ScLatticeIterationsGrowSlowerThanJacobiCg) {
  double it[2][2];  // [amg, cg][8³, 16³]
  for (int s = 0; s < 2; ++s) {
    Net sc;
    sc.net.packing = test::lattice("simple_cubic", s == 0 ? 8 : 16, 1e-3, 0.5e-3);
    test::bond_ratio(sc.net, 0.1);
    sc.laws = bond_laws(sc.net.packing, "", LawOptions{}, false);
    for (int p = 0; p < 2; ++p) {
      ImplicitOptions o;
      o.solver = p == 0 ? ElasticSolver::amg : ElasticSolver::cg;
      o.tolerance = 1e-10;
      o.full_tensor = false;  // three cases: iterations per case hardly differ between cases
      const ImplicitResult r = solve_implicit(sc.net.packing, sc.net.image, bond_stiffnesses(sc.net.packing, sc.laws), o);
      ASSERT_TRUE(r.converged);
      it[p][s] = double(r.iterations) / 3;
    }
  }
  std::printf("iterations per case, 8^3 -> 16^3: amg %.1f -> %.1f (x%.2f), Jacobi cg %.1f -> %.1f (x%.2f)\n", it[0][0],
              it[0][1], it[0][1] / it[0][0], it[1][0], it[1][1], it[1][1] / it[1][0]);
  EXPECT_LT(it[0][1] / it[0][0], 1.5);
  EXPECT_GT(it[1][1] / it[1][0], 1.5);
}
