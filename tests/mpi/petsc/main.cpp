// GoogleTest under mpirun: MPI around the tests, PETSc finalised before MPI; only rank 0 prints
// the test log (a failure on any rank still fails the run: every rank returns its own result).
#include <gtest/gtest.h>
#include <mpi.h>

#include "tomodem/linalg/petsc_solver.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int failed = RUN_ALL_TESTS();
  int any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  tomodem::petsc_finalize();
  MPI_Finalize();
  return any;
}
