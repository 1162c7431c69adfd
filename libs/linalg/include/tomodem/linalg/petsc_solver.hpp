#pragma once
// Conjugate gradients preconditioned by PETSc's algebraic multigrid (GAMG, or hypre's BoomerAMG
// through PETSc) on the same CSR systems as amg.hpp: the stiffness matrices of tomodem-young and
// tomodem-fracture (SLA) and the graph Laplacians of tomodem-conduct (docs/solvers.md). Built only
// with -DTOMODEM_MPI=ON; PETSc and MPI headers stay inside petsc_solver.cpp, so callers compile
// the same in both builds and a build without PETSc refuses the choice (require_petsc).
//
// PETSc owns a contiguous slice of nodes per rank (MPIAIJ on several ranks; owned_nodes). The
// tools assemble only their rank's rows (the distributed constructor, PetscRows) and every rank
// gets the whole solution back, so what they compute from it is the same on every rank. A whole
// system on every rank is still accepted (the first constructor: each rank takes its slice).
// Elastic systems keep their nodes' unknowns together (block size 3 or 6) and hand GAMG the
// rigid-body modes as its near-null space.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

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
  double nonzeros = 0;        ///< of the PETSc matrix, all ranks (identity rows included)
  int levels = 0;             ///< multigrid levels (GAMG)
  double setup_s = 0;         ///< matrix, near-null space and the last preconditioner set-up
};

/// This rank's rows of a distributed system: the unknowns [first, first + local rows) of
/// `unknowns` in all; they must be exactly the unknowns of the nodes PetscSolver::owned_nodes
/// gives this rank (unknowns numbered node by node, as every caller does).
struct PetscRows {
  int32_t unknowns = 0;
  int32_t first = 0;
};

/// One system in PETSc: matrix, CG + multigrid. Collective: every rank constructs it and calls
/// every method in the same order.
class PetscSolver {
 public:
  /// The nodes [first, last) whose rows this rank owns out of `nodes`: contiguous blocks of
  /// nodes·rank/size (node numbering unchanged). Initialises PETSc (and MPI) on first use; one
  /// rank, or the serial build: [0, nodes).
  static std::pair<int32_t, int32_t> owned_nodes(int32_t nodes);
  /// Distributed assembly: `local` holds this rank's rows only (row i is unknown rows.first + i,
  /// columns are whole-system unknowns; `start` may begin at any offset into column/value), `ns`
  /// describes the whole system (every unknown's node and kind, every node's position). solve()
  /// then takes this rank's rows of b. Preallocation from the local rows' counts.
  PetscSolver(const CsrView& local, const PetscRows& rows, const NearNullspace& ns, const PetscSolveOptions& options = {});
  /// `ns` as for Amg: empty node list = scalar (graph Laplacian, block size 1); otherwise the
  /// unknowns of a node are consecutive, their kinds translations (block 3) and rotations
  /// (block 6); a node's missing unknowns (pinned, or without stiffness) become identity rows.
  PetscSolver(const CsrView& A, const NearNullspace& ns, const PetscSolveOptions& options = {});
  ~PetscSolver();
  PetscSolver(const PetscSolver&) = delete;
  PetscSolver& operator=(const PetscSolver&) = delete;
  /// New values of A (the whole matrix, or this rank's rows for the distributed constructor).
  /// Same pattern: the values are replaced and GAMG keeps its interpolation (the coarse operators
  /// are recomputed: what Amg::replace_finest does); another pattern: rebuilt.
  void replace_matrix(const CsrView& A);
  /// b: the whole right-hand side (first constructor) or this rank's rows of it (distributed).
  /// x holds the initial guess (warm start) on entry and the solution on exit, whole, on every
  /// rank. The report's residual |b − A x| / |b| is recomputed by PETSc over all ranks.
  PcgReport solve(const double* b, double* x) const;
  const PetscStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tomodem
