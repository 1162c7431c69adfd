# PETSc's CG + GAMG against the in-house solvers (docs/solvers.md): the same E, ν, C_ij (young,
# implicit), σ (conduct) and SLA fracture sequence, on 1 and 2 ranks.
tomodem_mpi_test(petsc_mpi
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/petsc/main.cpp ${CMAKE_CURRENT_LIST_DIR}/petsc/petsc_agreement_test.cpp
  LIBS tomodem_mechanics tomodem_network tomodem_linalg tomodem_dem tomodem_core
  RANKS 1 2)
