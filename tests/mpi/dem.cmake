# The DEM engine on MPI domain decomposition (docs/dem.md, "Running on several ranks").
tomodem_mpi_test(dem_decomposition_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_decomposition.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)

# Scene A timings on ranks and threads (not a test; numbers for docs/scaling.md).
add_executable(dem_decomposition_bench ${CMAKE_CURRENT_SOURCE_DIR}/dem/bench_decomposed.cpp)
target_link_libraries(dem_decomposition_bench PRIVATE tomodem_dem tomodem_mpi)
add_dependencies(tomodem_mpi_tests dem_decomposition_bench)

# The worked example of docs/dem.md ("Running on several ranks"), as the page shows it.
add_test(NAME dem_decomposition_doc_example
  COMMAND sh ${CMAKE_CURRENT_SOURCE_DIR}/dem/doc_example.sh ${MPIEXEC_EXECUTABLE}
          $<TARGET_FILE:dem_decomposition_bench> ${CMAKE_SOURCE_DIR}/docs/dem.md)
set_tests_properties(dem_decomposition_doc_example PROPERTIES LABELS mpi PROCESSORS 3
  ENVIRONMENT "OMP_NUM_THREADS=1;OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")
