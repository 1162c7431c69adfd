// The cost model of `tomodem-young --solver auto` (docs/young.md, "How auto chooses"): operation
// counts from the particle graph, converted to CPU seconds by constants measured with the bench
// YoungBench.SolverCostTable (tests/bench/young). LDLT: the column counts of L in the approximate
// minimum degree order (Eigen's AMD, as SimplicialLDLT uses), counted on the particle graph and
// scaled by the unknowns per particle; CG: iterations per case × nonzeros of K.
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <vector>

#include "tomodem/mechanics/elastic.hpp"

namespace tomodem::mechanics {

namespace {
// Measured constants (YoungBench.SolverCostTable: random networks at Z 3.7, 5.0 and 6.5, N 100 to
// 10 000, six strain cases to 1e-10, one thread, Release; relative least squares, docs/young.md;
// the lattices are not in the fit: Jacobi converges on them far faster than on disordered
// networks). LDLT: a·flops^γ + b·nnz(K) (the time per flop of the simplicial factorisation grows
// with the factor: cache misses; b: ordering, symbolic analysis, copies). CG: seconds per nonzero
// of K per iteration (multigrid: one product with K, two block-Jacobi sweeps each side, the
// transfers and the coarse levels; its set-up is folded in, a separate set-up term fitted below
// zero). Iterations per case per decade of tolerance: exp(c0 + (c1 + c3 ln z) ln n + c2 ln z),
// n = N/1000, z = Z/4 (Z: bonded neighbours per particle).
constexpr double kLdltA = 2.173e-11, kLdltGamma = 1.16, kLdltB = 2.146e-7;
constexpr double kAmgSecondsPerNonzeroIteration = 6.47e-9;
constexpr double kCgSecondsPerNonzeroIteration = 8.66e-10;
// Multigrid iterations refitted with the rows at N = 10^5 (Z 3.7: 1177 per case, Z 6.5: 52; the fit
// to N ≤ 10^4 alone predicted 516 and 33); Jacobi's fit is unchanged (no 10^5 row measured).
constexpr double kAmgIter[4] = {2.1563, 0.4078, -2.5491, -0.6278};
constexpr double kCgIter[4] = {4.3815, 0.4865, -2.8686, -0.3219};
// The fit's range: outside it the model is held at its edge.
constexpr double kMinZ = 3.7, kMaxZ = 6.6, kMinN = 100, kMaxN = 1e5;

double iterations_per_decade(const double (&c)[4], double n, double Z) {
  const double ln = std::log(std::clamp(n, kMinN, kMaxN) / 1000), lz = std::log(std::clamp(Z, kMinZ, kMaxZ) / 4);
  return std::exp(c[0] + (c[1] + c[3] * lz) * ln + c[2] * lz);
}

struct Symbolic {
  double nonzeros = 0, flops = 0;
  bool truncated = false;
};

/// Column counts of the Cholesky factor of the particle graph (Liu's row-subtree walk on the
/// elimination tree: each step finds one nonzero of L, so the count costs O(nnz(L)) and stops at
/// `flop_limit` (in units of the block count Σ c_j²).
Symbolic block_factor_counts(const std::vector<std::vector<int64_t>>& graph, double flop_limit) {
  Symbolic out;
  const int n = int(graph.size());
  if (n == 0) return out;
  std::vector<Eigen::Triplet<double, int>> t;
  for (int a = 0; a < n; ++a)
    for (int64_t c : graph[std::size_t(a)]) t.emplace_back(a, int(c), 1.0);
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
  Eigen::AMDOrdering<int>()(A, pinv);  // the inverse permutation, as in SimplicialLDLT
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm = pinv.inverse();
  std::vector<int> parent(std::size_t(n), -1), flag(std::size_t(n), -1);
  std::vector<double> count(std::size_t(n), 0);
  double flops = 0, nnz = 0;
  for (int k = 0; k < n; ++k) {
    flag[std::size_t(k)] = k;
    for (int64_t c : graph[std::size_t(pinv.indices()[k])]) {
      for (int i = perm.indices()[int(c)]; i < k && flag[std::size_t(i)] != k; i = parent[std::size_t(i)]) {
        if (parent[std::size_t(i)] < 0) parent[std::size_t(i)] = k;
        flops += 2 * count[std::size_t(i)] + 1;  // (c + 1)² − c²
        count[std::size_t(i)] += 1;
        nnz += 1;
        flag[std::size_t(i)] = k;
      }
    }
    if (flops > flop_limit) {
      out.truncated = true;
      break;
    }
  }
  out.nonzeros = nnz;
  out.flops = flops;
  return out;
}
}  // namespace

SolverCosts solver_costs_from_counts(const SolverCosts& counts, int cases) {
  SolverCosts c = counts;
  const double nnz = c.matrix_nonzeros;
  c.amg_s = nnz * cases * c.amg_iterations * kAmgSecondsPerNonzeroIteration;
  c.cg_s = nnz * cases * c.cg_iterations * kCgSecondsPerNonzeroIteration;
  c.ldlt_s = kLdltA * std::pow(c.factor_flops, kLdltGamma) + kLdltB * nnz;
  c.cheapest = ElasticSolver::ldlt;
  double best = c.ldlt_s;
  if (c.amg_s < best) best = c.amg_s, c.cheapest = ElasticSolver::amg;
  if (c.cg_s < best) best = c.cg_s, c.cheapest = ElasticSolver::cg;
  return c;
}

SolverCosts predict_solver_costs(const std::vector<std::vector<int64_t>>& graph, long dofs, double nonzeros,
                                 int cases, double tolerance) {
  SolverCosts c;
  c.matrix_nonzeros = nonzeros;
  const double np = double(std::max<std::size_t>(1, graph.size()));
  const double b = double(dofs) / np;  // unknowns per particle (6, or 3 without moments)
  double entries = 0;
  for (const auto& row : graph) entries += double(row.size());
  c.coordination = entries / np - 1;  // the graph rows hold the particle itself
  const double decades = std::max(1.0, -std::log10(std::max(tolerance, 1e-16)));
  c.amg_iterations = decades * iterations_per_decade(kAmgIter, np, c.coordination);
  c.cg_iterations = decades * iterations_per_decade(kCgIter, np, c.coordination);
  c = solver_costs_from_counts(c, cases);  // the iterative paths first: they bound the count below
  // A block column with c block entries below the diagonal holds b columns of about b c entries
  // each: b³ c² multiply-adds; the count stops once LDLT would cost 8× the cheaper iterative path.
  const double budget = 8 * std::min(c.amg_s, c.cg_s);
  const double limit = std::pow(budget / kLdltA, 1 / kLdltGamma) / (b * b * b);
  const Symbolic s = block_factor_counts(graph, limit);
  c.factor_nonzeros = b * b * s.nonzeros + np * b * (b - 1) / 2;
  c.factor_flops = b * b * b * s.flops;
  c.factor_truncated = s.truncated;
  return solver_costs_from_counts(c, cases);
}

}  // namespace tomodem::mechanics
