#pragma once
// Conjugate gradients preconditioned by PETSc's algebraic multigrid (GAMG, or hypre's BoomerAMG
// through PETSc) on the same CSR systems as amg.hpp: the stiffness matrices of tomodem-young and
// tomodem-fracture (SLA) and the graph Laplacians of tomodem-conduct (docs/solvers.md). Built only
// with -DTOMODEM_MPI=ON; PETSc and MPI headers stay inside petsc_solver.cpp, so callers compile
// the same in both builds and a build without PETSc refuses the choice (require_petsc).
//
// Every rank holds the whole system (the callers assemble it on each rank, as in the serial run)
// and the right-hand side; PETSc owns a contiguous slice of nodes per rank (MPIAIJ on several
// ranks), and every rank gets the whole solution back. Elastic systems keep their nodes' unknowns
// together (block size 3 or 6) and hand GAMG the rigid-body modes as its near-null space.
#include <cstdint>
#include <memory>
#include <string>

#include "tomodem/linalg/amg.hpp"

namespace tomodem {

/// True in a build with PETSc (-DTOMODEM_MPI=ON).
bool petsc_available();

/// Throws InputError (exit 2) naming `option` in a build without PETSc: "this build has no PETSc;
/// configure with -DTOMODEM_MPI=ON". Tools call it where the choice is read, before any work.
void require_petsc(const std::string& option);

/// PetscFinalize, if PETSc was initialised here and MPI is still running. Whoever calls
/// MPI_Finalize calls this first; otherwise it runs at exit. PETSc is initialised lazily by the
/// first PetscSolver (PetscInitialize, on top of MPI when someone already initialised it).
void petsc_finalize();

enum class PetscPreconditioner : uint8_t { gamg, boomeramg };

struct PetscSolveOptions {
  PetscPreconditioner preconditioner = PetscPreconditioner::gamg;
  double tolerance = 1e-10;   ///< relative residual |b − A x| / |b| (unpreconditioned norm, as pcg())
  int max_iterations = 10000;
};

struct PetscStats {
  int ranks = 1;
  long rows = 0;              ///< of the PETSc matrix (unknowns plus padding to whole blocks)
  int block_size = 1;
  int levels = 0;             ///< multigrid levels (GAMG)
  double setup_s = 0;         ///< matrix, near-null space and the last preconditioner set-up
};

/// One system in PETSc: matrix, CG + multigrid. Collective: every rank constructs it with the
/// same A and calls every method in the same order.
class PetscSolver {
 public:
  /// `ns` as for Amg: empty node list = scalar (graph Laplacian, block size 1); otherwise the
  /// unknowns of a node are consecutive, their kinds translations (block 3) and rotations
  /// (block 6); a node's missing unknowns (pinned, or without stiffness) become identity rows.
  PetscSolver(const CsrView& A, const NearNullspace& ns, const PetscSolveOptions& options = {});
  ~PetscSolver();
  PetscSolver(const PetscSolver&) = delete;
  PetscSolver& operator=(const PetscSolver&) = delete;
  /// New values of A. Same pattern: the values are replaced and GAMG keeps its interpolation (the
  /// coarse operators are recomputed: what Amg::replace_finest does); another pattern: rebuilt.
  void replace_matrix(const CsrView& A);
  /// x holds the initial guess (warm start) on entry and the solution on exit, whole, on every
  /// rank. The report's residual is recomputed by PETSc after the solve.
  PcgReport solve(const double* b, double* x) const;
  const PetscStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tomodem
