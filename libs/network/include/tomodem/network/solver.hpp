#pragma once
// Kirchhoff's current law on a graph: a graph Laplacian solved by preconditioned conjugate
// gradients (Eigen, hidden in solver.cpp).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tomodem/network/graph.hpp"

namespace tomodem::network {

enum class Preconditioner {
  incomplete_cholesky,  ///< Eigen::IncompleteCholesky (Lin & Moré), natural ordering
  jacobi,               ///< diagonal scaling: cheapest set-up, multi-threaded apply
  amg,                  ///< smoothed-aggregation multigrid (tomodem/linalg/amg.hpp): iterations nearly independent of size
  petsc,                ///< PETSc's CG + GAMG (tomodem/linalg/petsc_solver.hpp), MPI build only (docs/solvers.md)
};
/// "ic" | "jacobi" | "amg" | "petsc" ("petsc" in a build without PETSc: InputError, exit 2)
Preconditioner parse_preconditioner(const std::string& name);
std::string to_string(Preconditioner p);

struct SolverOptions {
  double tolerance = 1e-10;  ///< relative residual |b - A v| / |b| to reach
  int max_iterations = 0;    ///< 0: 10 × unknowns, capped at 100000
  Preconditioner preconditioner = Preconditioner::incomplete_cholesky;
};

struct SolverReport {
  std::size_t unknowns = 0;     ///< free potentials solved for
  std::size_t nonzeros = 0;     ///< of the assembled matrix
  int iterations = 0;
  double residual = 0;          ///< relative residual recomputed after the solve
  bool converged = false;
  double assemble_time_s = 0, setup_time_s = 0, solve_time_s = 0;
  std::size_t memory_bytes = 0;  ///< matrix + preconditioner + CG vectors (estimate)
  int levels = 0;                  ///< amg: multigrid levels
  double operator_complexity = 0;  ///< amg: Σ nonzeros of all levels / nonzeros of the matrix
};

/// Solves  sum_j g_ij (v_i - v_j) = source_i  for the nodes with active[i] && !fixed[i].
/// Fixed nodes keep `potential[i]`; edges with an inactive endpoint are ignored. `source` may be
/// empty (no sources). On entry `potential` holds the fixed values and the initial guess, on exit
/// the solution (inactive nodes untouched). Every connected set of active free nodes must touch a
/// fixed node, else the matrix is singular (callers remove such clusters first).
SolverReport solve_kirchhoff(const Graph& graph, const std::vector<uint8_t>& active, const std::vector<uint8_t>& fixed,
                             const std::vector<double>& source, std::vector<double>& potential,
                             const SolverOptions& options);

}  // namespace tomodem::network
