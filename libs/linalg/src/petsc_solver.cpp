// PETSc's CG + GAMG (or BoomerAMG) on the CSR systems of amg.hpp (docs/solvers.md). Built only
// with -DTOMODEM_MPI=ON. Layout: the unknowns of node k go to rows k·bs + kind (bs = 1 scalar,
// 3 translations, 6 translations and rotations); rows without an unknown are identity rows with
// a zero right-hand side, so every node is a whole block and GAMG aggregates nodes. Rank r owns
// the nodes [r·n/size, (r+1)·n/size) (owned_nodes); with the distributed constructor the caller
// hands in only those rows, so no rank ever holds the whole matrix.
#include <mpi.h>
#include <petscksp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "tomodem/core/error.hpp"
#include "tomodem/linalg/petsc_solver.hpp"

namespace tomodem {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void check(PetscErrorCode e, const char* call) {
  if (e != 0) throw RuntimeFailure(std::string("PETSc: ") + call + " failed (error code " + std::to_string(int(e)) + ")");
}
#define TOMODEM_PETSC(call) check((call), #call)

void finalize_at_exit() { petsc_finalize(); }

/// PetscInitialize once per process, on top of MPI when another part already started it (then
/// PetscFinalize leaves MPI running); PETSc's signal handler stays off (the tools' own messages).
void ensure_petsc() {
  PetscBool initialised = PETSC_FALSE;
  TOMODEM_PETSC(PetscInitialized(&initialised));
  if (initialised) return;
  TOMODEM_PETSC(PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr));
  TOMODEM_PETSC(PetscInitializeNoArguments());
  static bool registered = false;
  if (!registered) std::atexit(finalize_at_exit), registered = true;
}

}  // namespace

bool petsc_available() { return true; }

void require_petsc(const std::string&) {}

void petsc_finalize() {
  PetscBool initialised = PETSC_FALSE, finalised = PETSC_FALSE;
  int mpi_finalised = 0;
  PetscInitialized(&initialised);
  PetscFinalized(&finalised);
  MPI_Finalized(&mpi_finalised);
  // After MPI_Finalize PETSc can no longer clean up; at exit that costs nothing.
  if (initialised && !finalised && !mpi_finalised) PetscFinalize();
}

struct PetscSolver::Impl {
  PetscSolveOptions o;
  PetscStats stats;
  int rank = 0, size = 1;
  int bs = 1;
  int32_t n_unknowns = 0;                // of the whole system
  int32_t row_base = 0;                  // unknown u is row u − row_base of the caller's CSR and b
  bool distributed = false;              // the caller's CSR holds this rank's rows only
  PetscInt n_rows = 0, lo = 0, hi = 0;   // global rows, owned rows [lo, hi)
  std::vector<int32_t> row_of;           // unknown -> PETSc row
  std::vector<int32_t> unknown_of;       // owned PETSc row - lo -> unknown (−1: identity row)
  std::vector<int32_t> pattern_start, pattern_column;  // the caller's CSR pattern (start from 0)
  double pad_diagonal = 1;               // identity rows, scaled like the matrix's diagonal
  NearNullspace ns;
  Mat A = nullptr;
  KSP ksp = nullptr;
  Vec b = nullptr, x = nullptr, x_all = nullptr, r = nullptr;
  VecScatter to_all = nullptr;

  ~Impl() { destroy(); }
  void destroy() {
    if (ksp) KSPDestroy(&ksp);
    if (A) MatDestroy(&A);
    if (b) VecDestroy(&b);
    if (x) VecDestroy(&x);
    if (r) VecDestroy(&r);
    if (x_all) VecDestroy(&x_all);
    if (to_all) VecScatterDestroy(&to_all);
  }
  void init(const CsrView& view);
  void layout(const CsrView& view);
  void build_matrix(const CsrView& view);
  void set_values(const CsrView& view);
  void set_near_nullspace();
  void build_solver();
  void setup();
  /// The caller's CSR row of unknown u.
  int32_t csr_row(int32_t u) const { return u - row_base; }
};

/// Row numbering, block size and the owned rows; checks that a distributed caller handed in
/// exactly the unknowns of this rank's nodes.
void PetscSolver::Impl::layout(const CsrView& view) {
  const int32_t n = n_unknowns;
  row_of.resize(std::size_t(n));
  int32_t nodes = n;
  if (ns.node.empty()) {
    bs = 1;
    for (int32_t u = 0; u < n; ++u) row_of[std::size_t(u)] = u;
  } else {
    if (ns.node.size() != std::size_t(n) || ns.kind.size() != std::size_t(n))
      throw RuntimeFailure("PETSc solver: the near-null space does not match the matrix size");
    bool rotations = false;
    nodes = int32_t(ns.position.size());
    for (int32_t u = 0; u < n; ++u) {
      rotations |= ns.kind[std::size_t(u)] >= NearNullspace::rx;
      nodes = std::max(nodes, ns.node[std::size_t(u)] + 1);
    }
    bs = rotations ? 6 : 3;
    for (int32_t u = 0; u < n; ++u) row_of[std::size_t(u)] = ns.node[std::size_t(u)] * bs + ns.kind[std::size_t(u)];
  }
  n_rows = PetscInt(nodes) * bs;
  lo = PetscInt(int64_t(nodes) * rank / size) * bs;
  hi = PetscInt(int64_t(nodes) * (rank + 1) / size) * bs;
  unknown_of.assign(std::size_t(hi - lo), -1);
  int32_t owned = 0, owned_first = n;
  for (int32_t u = 0; u < n; ++u) {
    const int32_t row = row_of[std::size_t(u)];
    if (row >= lo && row < hi) unknown_of[std::size_t(row - lo)] = u, ++owned, owned_first = std::min(owned_first, u);
  }
  if (distributed) {
    int ok = owned == view.rows && (owned == 0 || owned_first == row_base) && row_base >= 0 &&
             int64_t(row_base) + view.rows <= n;
    for (int32_t i = 0; ok && i < view.rows; ++i) {
      const int32_t row = row_of[std::size_t(row_base + i)];
      ok = row >= lo && row < hi;
    }
    int all_ok = ok;  // every rank throws, or none: the calls that follow are collective
    MPI_Allreduce(MPI_IN_PLACE, &all_ok, 1, MPI_INT, MPI_LAND, PETSC_COMM_WORLD);
    if (!all_ok && ok) throw RuntimeFailure("PETSc solver: another rank was given rows that are not its own");
    if (!ok)
      throw RuntimeFailure("PETSc solver: rank " + std::to_string(rank) + " was given the unknowns [" +
                           std::to_string(row_base) + ", " + std::to_string(row_base + view.rows) +
                           ") but owns the " + std::to_string(owned) + " unknowns of the nodes [" +
                           std::to_string(lo / bs) + ", " + std::to_string(hi / bs) + ")");
  }
  // The mean |diagonal| over all unknowns: local sums, reduced over the ranks.
  double sums[2] = {0, 0};
  for (PetscInt i = 0; i < hi - lo; ++i) {
    const int32_t u = unknown_of[std::size_t(i)];
    if (u < 0) continue;
    const int32_t cr = csr_row(u);
    for (int32_t k = view.start[cr]; k < view.start[cr + 1]; ++k)
      if (view.column[k] == u) sums[0] += std::abs(view.value[k]);
    sums[1] += 1;
  }
  MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  pad_diagonal = sums[1] > 0 && sums[0] > 0 ? sums[0] / sums[1] : 1.0;
  stats.rows = long(n_rows);
  stats.block_size = bs;
  stats.ranks = size;
}

/// AIJ (MPIAIJ on several ranks) preallocated from the owned rows' diagonal/off-diagonal counts.
void PetscSolver::Impl::build_matrix(const CsrView& view) {
  const PetscInt local = hi - lo;
  std::vector<PetscInt> d_nnz(std::size_t(local), 1), o_nnz(std::size_t(local), 0);
  for (PetscInt i = 0; i < local; ++i) {
    const int32_t u = unknown_of[std::size_t(i)];
    if (u < 0) continue;
    const int32_t cr = csr_row(u);
    d_nnz[std::size_t(i)] = 0;
    for (int32_t k = view.start[cr]; k < view.start[cr + 1]; ++k) {
      const int32_t c = row_of[std::size_t(view.column[k])];
      ++(c >= lo && c < hi ? d_nnz : o_nnz)[std::size_t(i)];
    }
  }
  TOMODEM_PETSC(MatCreate(PETSC_COMM_WORLD, &A));
  TOMODEM_PETSC(MatSetSizes(A, local, local, n_rows, n_rows));
  TOMODEM_PETSC(MatSetBlockSize(A, bs));
  TOMODEM_PETSC(MatSetType(A, MATAIJ));
  TOMODEM_PETSC(MatSeqAIJSetPreallocation(A, 0, d_nnz.data()));
  TOMODEM_PETSC(MatMPIAIJSetPreallocation(A, 0, d_nnz.data(), 0, o_nnz.data()));
  // The systems are symmetric: GAMG then skips symmetrising its graph.
  TOMODEM_PETSC(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));
  TOMODEM_PETSC(MatSetOption(A, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
  pattern_start.resize(std::size_t(view.rows) + 1);
  for (int32_t i = 0; i <= view.rows; ++i) pattern_start[std::size_t(i)] = view.start[i] - view.start[0];
  pattern_column.assign(view.column + view.start[0], view.column + view.start[view.rows]);
  set_values(view);
  MatInfo mi;
  TOMODEM_PETSC(MatGetInfo(A, MAT_GLOBAL_SUM, &mi));
  stats.nonzeros = double(mi.nz_used);
  TOMODEM_PETSC(MatCreateVecs(A, &x, &b));
  TOMODEM_PETSC(VecDuplicate(b, &r));
  TOMODEM_PETSC(VecScatterCreateToAll(x, &to_all, &x_all));
}

void PetscSolver::Impl::set_values(const CsrView& view) {
  std::vector<PetscInt> cols;
  for (PetscInt i = 0; i < hi - lo; ++i) {
    const PetscInt row = lo + i;
    const int32_t u = unknown_of[std::size_t(i)];
    if (u < 0) {
      TOMODEM_PETSC(MatSetValue(A, row, row, pad_diagonal, INSERT_VALUES));
      continue;
    }
    const int32_t cr = csr_row(u);
    const int32_t k0 = view.start[cr], nk = view.start[cr + 1] - k0;
    cols.resize(std::size_t(nk));
    for (int32_t k = 0; k < nk; ++k) cols[std::size_t(k)] = row_of[std::size_t(view.column[k0 + k])];
    TOMODEM_PETSC(MatSetValues(A, 1, &row, nk, cols.data(), view.value + k0, INSERT_VALUES));
  }
  TOMODEM_PETSC(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
  TOMODEM_PETSC(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
}

/// The rigid-body modes of the nodes (three translations, three rotations about the centroid;
/// rotation unknowns are rotation_scale × angle), orthonormalised for MatNullSpaceCreate. Identity
/// rows carry zeros. Periodic cells: the lever arms are the stored positions (a mode is only
/// approximate where an aggregate straddles the boundary; GAMG stays a valid preconditioner).
void PetscSolver::Impl::set_near_nullspace() {
  if (bs == 1) return;  // GAMG's default for scalars: the constant vector
  Vec modes[6];
  Vec3 centre{0, 0, 0};
  for (const Vec3& p : ns.position) centre = centre + p;
  if (!ns.position.empty()) centre = centre * (1.0 / double(ns.position.size()));
  for (int m = 0; m < 6; ++m) {
    TOMODEM_PETSC(VecDuplicate(b, &modes[m]));
    PetscScalar* v = nullptr;
    TOMODEM_PETSC(VecGetArray(modes[m], &v));
    for (PetscInt i = 0; i < hi - lo; ++i) {
      const int32_t u = unknown_of[std::size_t(i)];
      double value = 0;
      if (u >= 0) {
        const int kind = ns.kind[std::size_t(u)];
        const Vec3 d = ns.position[std::size_t(ns.node[std::size_t(u)])] - centre;
        if (m < 3) {
          value = kind == m ? 1.0 : 0.0;  // translation along m
        } else if (kind < 3) {             // rotation about axis m − 3: (e × d)_kind
          const int a = m - 3;
          const double dc[3] = {d.x, d.y, d.z};
          const int k1 = (a + 1) % 3, k2 = (a + 2) % 3;
          value = kind == k1 ? -dc[k2] : kind == k2 ? dc[k1] : 0.0;
        } else {
          value = kind - 3 == m - 3 ? ns.rotation_scale : 0.0;
        }
      }
      v[i] = value;
    }
    TOMODEM_PETSC(VecRestoreArray(modes[m], &v));
    for (int q = 0; q < m; ++q) {  // modified Gram–Schmidt
      PetscScalar dot = 0;
      TOMODEM_PETSC(VecDot(modes[m], modes[q], &dot));
      TOMODEM_PETSC(VecAXPY(modes[m], -dot, modes[q]));
    }
    TOMODEM_PETSC(VecNormalize(modes[m], nullptr));
  }
  MatNullSpace space = nullptr;
  TOMODEM_PETSC(MatNullSpaceCreate(PETSC_COMM_WORLD, PETSC_FALSE, 6, modes, &space));
  TOMODEM_PETSC(MatSetNearNullSpace(A, space));
  TOMODEM_PETSC(MatNullSpaceDestroy(&space));
  for (Vec& m : modes) TOMODEM_PETSC(VecDestroy(&m));
}

/// CG on the unpreconditioned residual (the in-house criterion), multigrid preconditioner;
/// PETSC_OPTIONS (e.g. "-ksp_monitor", "-pc_type hypre") may override afterwards.
void PetscSolver::Impl::build_solver() {
  TOMODEM_PETSC(KSPCreate(PETSC_COMM_WORLD, &ksp));
  TOMODEM_PETSC(KSPSetOperators(ksp, A, A));
  TOMODEM_PETSC(KSPSetType(ksp, KSPCG));
  TOMODEM_PETSC(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  TOMODEM_PETSC(KSPSetTolerances(ksp, o.tolerance, PETSC_DEFAULT, PETSC_DEFAULT, o.max_iterations));
  TOMODEM_PETSC(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE));
  PC pc = nullptr;
  TOMODEM_PETSC(KSPGetPC(ksp, &pc));
  if (o.preconditioner == PetscPreconditioner::boomeramg) {
    TOMODEM_PETSC(PCSetType(pc, PCHYPRE));
    TOMODEM_PETSC(PCHYPRESetType(pc, "boomeramg"));
  } else {
    TOMODEM_PETSC(PCSetType(pc, PCGAMG));
    TOMODEM_PETSC(PCGAMGSetReuseInterpolation(pc, PETSC_TRUE));
    // Chebyshev smoothing with point Jacobi took 3x the iterations of the in-house multigrid on
    // the 6-DOF networks (494 against 166 per strain case at 10^5 unknowns); point-block Jacobi
    // (the particle's 6x6 block, as the in-house smoother) 156. A user's PETSC_OPTIONS decides.
    PetscBool set = PETSC_FALSE;
    TOMODEM_PETSC(PetscOptionsHasName(nullptr, nullptr, "-mg_levels_pc_type", &set));
    if (!set && bs > 1) TOMODEM_PETSC(PetscOptionsSetValue(nullptr, "-mg_levels_pc_type", "pbjacobi"));
  }
  TOMODEM_PETSC(KSPSetFromOptions(ksp));
}

void PetscSolver::Impl::setup() {
  const auto t0 = Clock::now();
  TOMODEM_PETSC(KSPSetUp(ksp));
  PC pc = nullptr;
  TOMODEM_PETSC(KSPGetPC(ksp, &pc));
  PetscBool is_mg = PETSC_FALSE;
  TOMODEM_PETSC(PetscObjectTypeCompare(PetscObject(pc), PCGAMG, &is_mg));
  PetscInt levels = 0;
  if (is_mg) TOMODEM_PETSC(PCMGGetLevels(pc, &levels));
  stats.levels = int(levels);
  stats.setup_s = seconds_since(t0);
}

std::pair<int32_t, int32_t> PetscSolver::owned_nodes(int32_t nodes) {
  ensure_petsc();
  int rank = 0, size = 1;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  return {int32_t(int64_t(nodes) * rank / size), int32_t(int64_t(nodes) * (rank + 1) / size)};
}

void PetscSolver::Impl::init(const CsrView& view) {
  const auto t0 = Clock::now();
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  layout(view);
  build_matrix(view);
  set_near_nullspace();
  build_solver();
  const double assembly_s = seconds_since(t0);
  setup();
  stats.setup_s += assembly_s;
}

PetscSolver::PetscSolver(const CsrView& view, const NearNullspace& ns, const PetscSolveOptions& options)
    : impl_(std::make_unique<Impl>()) {
  ensure_petsc();
  Impl& m = *impl_;
  m.o = options;
  m.ns = ns;
  m.n_unknowns = view.rows;
  m.init(view);
}

PetscSolver::PetscSolver(const CsrView& local, const PetscRows& rows, const NearNullspace& ns,
                         const PetscSolveOptions& options)
    : impl_(std::make_unique<Impl>()) {
  ensure_petsc();
  Impl& m = *impl_;
  m.o = options;
  m.ns = ns;
  m.n_unknowns = rows.unknowns;
  m.row_base = rows.first;
  m.distributed = true;
  m.init(local);
}

PetscSolver::~PetscSolver() = default;

void PetscSolver::replace_matrix(const CsrView& view) {
  Impl& m = *impl_;
  int same = view.rows == int32_t(m.pattern_start.size()) - 1 &&
             std::equal(m.pattern_column.begin(), m.pattern_column.end(), view.column + view.start[0]);
  for (int32_t i = 0; same && i <= view.rows; ++i) same = view.start[i] - view.start[0] == m.pattern_start[std::size_t(i)];
  // Each rank sees its own rows: all rebuild if any pattern changed (the calls are collective).
  MPI_Allreduce(MPI_IN_PLACE, &same, 1, MPI_INT, MPI_LAND, PETSC_COMM_WORLD);
  if (!same) {  // another pattern: a new matrix and a fresh hierarchy
    auto fresh = std::make_unique<Impl>();
    fresh->o = m.o;
    fresh->ns = std::move(m.ns);
    fresh->n_unknowns = m.n_unknowns;
    fresh->row_base = m.row_base;
    fresh->distributed = m.distributed;
    impl_.reset();  // the old PETSc objects go first, on every rank
    impl_ = std::move(fresh);
    impl_->init(view);
    return;
  }
  const auto t0 = Clock::now();
  m.set_values(view);
  TOMODEM_PETSC(KSPSetOperators(m.ksp, m.A, m.A));
  m.setup();
  m.stats.setup_s = seconds_since(t0);
}

PcgReport PetscSolver::solve(const double* rhs, double* solution) const {
  const Impl& m = *impl_;
  const auto t0 = Clock::now();
  PcgReport rep;
  // b: the caller's rows (whole, or this rank's); x: whole.
  auto fill = [&](Vec v, const double* from, int32_t base) {
    PetscScalar* a = nullptr;
    TOMODEM_PETSC(VecGetArray(v, &a));
    for (PetscInt i = 0; i < m.hi - m.lo; ++i) {
      const int32_t u = m.unknown_of[std::size_t(i)];
      a[i] = u >= 0 ? from[u - base] : 0.0;
    }
    TOMODEM_PETSC(VecRestoreArray(v, &a));
  };
  fill(m.b, rhs, m.row_base);
  fill(m.x, solution, 0);
  PetscReal bnorm = 0, rnorm = 0;
  TOMODEM_PETSC(VecNorm(m.b, NORM_2, &bnorm));  // over all ranks: every rank takes the same branch
  if (bnorm == 0) {  // no drive: the solution is zero (CG would chase an absolute tolerance of 1e-50)
    TOMODEM_PETSC(VecSet(m.x, 0.0));
    rep.converged = true;
  } else {
    TOMODEM_PETSC(KSPSolve(m.ksp, m.b, m.x));
    PetscInt its = 0;
    KSPConvergedReason reason;
    TOMODEM_PETSC(KSPGetIterationNumber(m.ksp, &its));
    TOMODEM_PETSC(KSPGetConvergedReason(m.ksp, &reason));
    rep.iterations = int(its);
    rep.converged = reason > 0;
    // |b − A x| / |b| recomputed, as pcg() reports it.
    TOMODEM_PETSC(MatMult(m.A, m.x, m.r));
    TOMODEM_PETSC(VecAYPX(m.r, -1.0, m.b));
    TOMODEM_PETSC(VecNorm(m.r, NORM_2, &rnorm));
    rep.residual = double(rnorm / bnorm);
  }
  TOMODEM_PETSC(VecScatterBegin(m.to_all, m.x, m.x_all, INSERT_VALUES, SCATTER_FORWARD));
  TOMODEM_PETSC(VecScatterEnd(m.to_all, m.x, m.x_all, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar* all = nullptr;
  TOMODEM_PETSC(VecGetArrayRead(m.x_all, &all));
  for (std::size_t u = 0; u < m.row_of.size(); ++u) solution[u] = all[m.row_of[u]];
  TOMODEM_PETSC(VecRestoreArrayRead(m.x_all, &all));
  rep.seconds = seconds_since(t0);
  return rep;
}

const PetscStats& PetscSolver::stats() const { return impl_->stats; }

}  // namespace tomodem
