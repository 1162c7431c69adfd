#include "tomodem/network/solver.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "tomodem/linalg/amg.hpp"
#include "tomodem/linalg/petsc_solver.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem::network {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Row-major so that Eigen's CG (Lower|Upper) runs the matrix-vector product on all threads.
using SpMat = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

int iteration_cap(const SolverOptions& opt, const SolverReport& rep) {
  return opt.max_iterations > 0
             ? opt.max_iterations
             : static_cast<int>(std::min<std::size_t>(100000, 10 * std::max<std::size_t>(rep.unknowns, 10)));
}

template <class Solver>
void run_cg(Solver& cg, const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, const SolverOptions& opt,
            SolverReport& rep) {
  const auto t0 = Clock::now();
  cg.setTolerance(opt.tolerance);
  cg.setMaxIterations(iteration_cap(opt, rep));
  cg.compute(A);
  if (cg.info() != Eigen::Success) throw NumericalError("preconditioner set-up failed (matrix not positive definite)");
  rep.setup_time_s = seconds_since(t0);
  const auto t1 = Clock::now();
  x = cg.solveWithGuess(b, x);
  rep.solve_time_s = seconds_since(t1);
  rep.iterations = static_cast<int>(cg.iterations());
  rep.converged = cg.info() == Eigen::Success;
}
}  // namespace

namespace {
/// PETSc's CG + GAMG (constant near-null space) with the rows split across the MPI ranks: each
/// rank assembles only the rows of its own unknowns (PetscSolver::owned_nodes; an edge between
/// two ranks' nodes is assembled by both, each its row), so no rank holds the whole Laplacian.
/// The solution comes back whole on every rank, the residual and nonzeros summed over the ranks.
SolverReport solve_petsc(const Graph& graph, const std::vector<uint8_t>& active, const std::vector<int32_t>& index,
                         int32_t nf, const std::vector<double>& source, std::vector<double>& potential,
                         const SolverOptions& opt, SolverReport rep, Clock::time_point t0) {
  const std::size_t n = graph.n_nodes;
  const auto [u0, u1] = PetscSolver::owned_nodes(nf);
  const int32_t nl = u1 - u0;
  auto own = [&](int32_t u) { return u >= u0 && u < u1; };
  std::vector<int32_t> deg(std::size_t(nl), 1);
  for (std::size_t e = 0; e < graph.n_edges(); ++e) {
    const int32_t a = graph.i[e], b = graph.j[e];
    if (!active[a] || !active[b]) continue;
    const int32_t ia = index[a], ib = index[b];
    if (ia >= 0 && ib >= 0) {
      if (own(ia)) ++deg[std::size_t(ia - u0)];
      if (own(ib)) ++deg[std::size_t(ib - u0)];
    }
  }
  SpMat A(nl, nf);
  A.reserve(deg);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nl), x(nf);
  std::vector<double> diag(std::size_t(nl), 0.0);
  for (std::size_t e = 0; e < graph.n_edges(); ++e) {
    const int32_t a = graph.i[e], b = graph.j[e];
    if (!active[a] || !active[b]) continue;
    const double g = graph.g[e];
    const int32_t ia = index[a], ib = index[b];
    if (ia >= 0 && own(ia)) {
      diag[std::size_t(ia - u0)] += g;
      if (ib >= 0) A.coeffRef(ia - u0, ib) -= g;
      else rhs[ia - u0] += g * potential[b];
    }
    if (ib >= 0 && own(ib)) {
      diag[std::size_t(ib - u0)] += g;
      if (ia >= 0) A.coeffRef(ib - u0, ia) -= g;
      else rhs[ib - u0] += g * potential[a];
    }
  }
  for (int32_t k = u0; k < u1; ++k) A.coeffRef(k - u0, k) = diag[std::size_t(k - u0)];
  A.makeCompressed();
  for (std::size_t v = 0; v < n; ++v)
    if (index[v] >= 0) {
      x[index[v]] = std::isfinite(potential[v]) ? potential[v] : 0.0;
      if (!source.empty() && own(index[v])) rhs[index[v] - u0] += source[v];
    }
  rep.assemble_time_s = seconds_since(t0);
  PetscSolveOptions po;
  po.tolerance = opt.tolerance;
  po.max_iterations = iteration_cap(opt, rep);
  const PetscSolver solver(CsrView{nl, A.outerIndexPtr(), A.innerIndexPtr(), A.valuePtr()}, PetscRows{nf, u0},
                           NearNullspace{}, po);
  rep.setup_time_s = solver.stats().setup_s;  // without PETSc's (and MPI's) one-time initialisation
  rep.nonzeros = static_cast<std::size_t>(solver.stats().nonzeros);
  // A zero right-hand side gives x = 0 in PETSc's CG too (b = 0 is converged at once).
  const PcgReport pr = solver.solve(rhs.data(), x.data());
  rep.solve_time_s = pr.seconds;
  rep.iterations = pr.iterations;
  rep.converged = pr.converged && std::isfinite(pr.residual);
  rep.residual = pr.residual;
  rep.levels = solver.stats().levels;
  // This rank's rows of A, its vectors and the whole solution; PETSc's own copy and hierarchy not counted.
  rep.memory_bytes = 12 * std::size_t(A.nonZeros()) + 8 * 4 * std::size_t(nl) + 8 * std::size_t(nf);
  for (std::size_t v = 0; v < n; ++v)
    if (index[v] >= 0) potential[v] = x[index[v]];
  return rep;
}
}  // namespace

Preconditioner parse_preconditioner(const std::string& name) {
  if (name == "ic") return Preconditioner::incomplete_cholesky;
  if (name == "jacobi") return Preconditioner::jacobi;
  if (name == "amg") return Preconditioner::amg;
  if (name == "petsc") {
    require_petsc("--preconditioner");
    return Preconditioner::petsc;
  }
  throw InputError("", "--preconditioner", name, "expected 'ic', 'jacobi', 'amg' or 'petsc'");
}

std::string to_string(Preconditioner p) {
  return p == Preconditioner::jacobi ? "jacobi" : p == Preconditioner::amg ? "amg" : p == Preconditioner::petsc ? "petsc" : "ic";
}

SolverReport solve_kirchhoff(const Graph& graph, const std::vector<uint8_t>& active, const std::vector<uint8_t>& fixed,
                             const std::vector<double>& source, std::vector<double>& potential,
                             const SolverOptions& opt) {
  const auto t0 = Clock::now();
  const std::size_t n = graph.n_nodes;
  SolverReport rep;
  std::vector<int32_t> index(n, -1);
  int32_t nf = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (active[v] && !fixed[v]) index[v] = nf++;
  rep.unknowns = static_cast<std::size_t>(nf);
  if (nf == 0) return rep;

  if (opt.preconditioner == Preconditioner::petsc) return solve_petsc(graph, active, index, nf, source, potential, opt, rep, t0);

  // Assemble row by row (CSR): diagonal first, then free neighbours; duplicates are summed.
  std::vector<int32_t> deg(nf, 1);
  for (std::size_t e = 0; e < graph.n_edges(); ++e) {
    const int32_t a = graph.i[e], b = graph.j[e];
    if (!active[a] || !active[b]) continue;
    if (index[a] >= 0 && index[b] >= 0) { ++deg[index[a]]; ++deg[index[b]]; }
  }
  SpMat A(nf, nf);
  A.reserve(deg);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nf), x(nf);
  std::vector<double> diag(nf, 0.0);
  for (std::size_t e = 0; e < graph.n_edges(); ++e) {
    const int32_t a = graph.i[e], b = graph.j[e];
    if (!active[a] || !active[b]) continue;
    const double g = graph.g[e];
    const int32_t ia = index[a], ib = index[b];
    if (ia >= 0) diag[ia] += g;
    if (ib >= 0) diag[ib] += g;
    if (ia >= 0 && ib >= 0) {
      A.coeffRef(ia, ib) -= g;
      A.coeffRef(ib, ia) -= g;
    } else if (ia >= 0) {
      rhs[ia] += g * potential[b];
    } else if (ib >= 0) {
      rhs[ib] += g * potential[a];
    }
  }
  for (int32_t k = 0; k < nf; ++k) A.coeffRef(k, k) = diag[k];
  A.makeCompressed();
  for (std::size_t v = 0; v < n; ++v)
    if (index[v] >= 0) {
      x[index[v]] = std::isfinite(potential[v]) ? potential[v] : 0.0;
      if (!source.empty()) rhs[index[v]] += source[v];
    }
  rep.nonzeros = static_cast<std::size_t>(A.nonZeros());
  rep.assemble_time_s = seconds_since(t0);

  // Threads only pay for large systems: below ~1e5 unknowns a matrix-vector product takes
  // microseconds and OpenMP synchronisation (worse on a loaded machine) dominates.
  const int saved_threads = Eigen::nbThreads();
  Eigen::setNbThreads(nf >= 100000 ? saved_threads : 1);
  const double bnorm = rhs.norm();
  if (bnorm == 0.0) {  // no drive: the solution is zero
    x.setZero();
  } else if (opt.preconditioner == Preconditioner::amg) {
    // Smoothed-aggregation multigrid (tomodem/linalg/amg.hpp) with the constant vector as the
    // near-null space of the Laplacian; its own OpenMP loops (above 5e4 unknowns) and CG.
    const auto ts = Clock::now();
    const CsrView view{nf, A.outerIndexPtr(), A.innerIndexPtr(), A.valuePtr()};
    AmgOptions ao;
    ao.strength = 0;  // every coupling: larger aggregates, operator complexity ~1.5 instead of ~2.2 at 0.08
    const Amg amg(view, NearNullspace{}, ao);
    rep.setup_time_s = seconds_since(ts);
    const PcgReport pr = pcg(view, &amg, rhs.data(), x.data(), opt.tolerance, iteration_cap(opt, rep));
    rep.solve_time_s = pr.seconds;
    rep.iterations = pr.iterations;
    rep.converged = pr.converged;
    rep.memory_bytes = 12 * rep.nonzeros + amg.stats().memory_bytes + 8 * 5 * (std::size_t)nf;
    rep.levels = static_cast<int>(amg.stats().rows.size());
    rep.operator_complexity = amg.stats().operator_complexity;
  } else if (opt.preconditioner == Preconditioner::jacobi) {
    Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg;
    run_cg(cg, A, rhs, x, opt, rep);
    rep.memory_bytes = 12 * rep.nonzeros + 4 * (std::size_t)nf + 8 * 6 * (std::size_t)nf;
  } else {
    Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper,
                             Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::NaturalOrdering<int>>>
        cg;
    run_cg(cg, A, rhs, x, opt, rep);
    // The factor L holds about half of A's non-zeros plus the same again of fill (Lin & Moré keep
    // as many entries per column as the column of A has), stored column-major.
    rep.memory_bytes = 12 * rep.nonzeros + 12 * rep.nonzeros + 4 * (std::size_t)nf + 8 * 7 * (std::size_t)nf;
  }
  Eigen::setNbThreads(saved_threads);
  rep.residual = bnorm == 0.0 ? 0.0 : (rhs - A * x).norm() / bnorm;
  // CG stops on its recursively updated residual; the recomputed one may differ by round-off.
  if (bnorm == 0.0) rep.converged = true;
  if (!std::isfinite(rep.residual)) rep.converged = false;
  for (std::size_t v = 0; v < n; ++v)
    if (index[v] >= 0) potential[v] = x[index[v]];
  return rep;
}

}  // namespace tomodem::network
