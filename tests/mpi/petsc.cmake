# PETSc's CG + GAMG against the in-house solvers (docs/solvers.md): the same E, ν, C_ij (young,
# implicit), σ (conduct) and SLA fracture sequence, on 1 and 2 ranks.
tomodem_mpi_test(petsc_mpi PETSC
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/petsc/petsc_agreement_test.cpp
  LIBS tomodem_mechanics tomodem_network tomodem_linalg tomodem_dem tomodem_core
  RANKS 1 2)

# The worked example of docs/solvers.md, run as the page writes it (pack, bond, young with the
# in-house multigrid, then mpirun -np 2 with PETSc) and checked (docs_example.py). Not under
# mpirun itself: the page's block calls mpirun.
find_package(Python3 REQUIRED COMPONENTS Interpreter)
add_test(NAME petsc_docs_example
  COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_LIST_DIR}/petsc/docs_example.py ${CMAKE_SOURCE_DIR} ${CMAKE_BINARY_DIR}/bin)
set_tests_properties(petsc_docs_example PROPERTIES LABELS mpi PROCESSORS 2
  ENVIRONMENT "OMP_NUM_THREADS=1;OMPI_MCA_rmaps_base_oversubscribe=1;OMPI_MCA_mpi_yield_when_idle=1;OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")
add_dependencies(tomodem_mpi_tests tomodem-pack tomodem-bond tomodem-young)

# Rank 0 alone speaks and writes (docs/scaling.md): young, conduct and fracture with PETSc under
# mpirun -np 2 print one summary, write only the named files, equal to the serial run's to the
# solver tolerance; bad input: one message, exit 2 on both ranks, nothing left behind.
add_test(NAME petsc_ranks_output
  COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_LIST_DIR}/petsc/ranks_output.py ${CMAKE_BINARY_DIR}/bin
          ${CMAKE_SOURCE_DIR} ${MPIEXEC_EXECUTABLE})
set_tests_properties(petsc_ranks_output PROPERTIES LABELS mpi PROCESSORS 2 ENVIRONMENT "OMPI_MCA_mpi_yield_when_idle=1")
add_dependencies(tomodem_mpi_tests tomodem-conduct tomodem-fracture)
