// The serial build (without -DTOMODEM_MPI=ON): no PETSc. The choice `petsc` is refused with exit 2
// where it is read (require_petsc); a PetscSolver constructed anyway refuses the same way.
#include "tomodem/core/error.hpp"
#include "tomodem/linalg/petsc_solver.hpp"

namespace tomodem {

namespace {
const char* const kNoPetsc = "this build has no PETSc; configure with -DTOMODEM_MPI=ON";
}

bool petsc_available() { return false; }

void require_petsc(const std::string& option) { throw InputError("", option, "petsc", kNoPetsc); }

void petsc_finalize() {}

struct PetscSolver::Impl {
  PetscStats stats;
};

PetscSolver::PetscSolver(const CsrView&, const NearNullspace&, const PetscSolveOptions&) {
  throw InputError("", "solver", "petsc", kNoPetsc);
}
PetscSolver::PetscSolver(const CsrView&, const PetscRows&, const NearNullspace&, const PetscSolveOptions&) {
  throw InputError("", "solver", "petsc", kNoPetsc);
}
std::pair<int32_t, int32_t> PetscSolver::owned_nodes(int32_t nodes) { return {0, nodes}; }
PetscSolver::~PetscSolver() = default;
void PetscSolver::replace_matrix(const CsrView&) {}
PcgReport PetscSolver::solve(const double*, double*) const { return {}; }
const PetscStats& PetscSolver::stats() const { return impl_->stats; }

}  // namespace tomodem
