# The DEM engine on MPI domain decomposition (docs/dem.md, "Running on several ranks").
tomodem_mpi_test(dem_decomposition_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_decomposition.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)
