// The main of every MPI GoogleTest executable (tomodem_mpi_test adds it): the tests inside
// MPI_Init/MPI_Finalize, results printed by rank 0 only, and the worst exit code of all ranks
// returned by each (a failure on any rank fails the run). Executables declared PETSC finalise
// PETSc before MPI.
#include <gtest/gtest.h>
#include <mpi.h>

#if TOMODEM_TEST_PETSC
#include "tomodem/linalg/petsc_solver.hpp"
#endif

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int rc = RUN_ALL_TESTS();
  int worst = rc;
  MPI_Allreduce(&rc, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
#if TOMODEM_TEST_PETSC
  tomodem::petsc_finalize();
#endif
  MPI_Finalize();
  return worst;
}
