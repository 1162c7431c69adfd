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
  ENVIRONMENT "OMP_NUM_THREADS=1;OMPI_MCA_mpi_yield_when_idle=1;OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")

# tomodem-dem started by mpirun on 1, 2 and 3 ranks against its run without mpirun: the test
# starts the launcher itself (it is not an MPI program), so it is an ordinary executable.
add_executable(dem_tool_ranks_tests ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_dem_tool.cpp)
target_link_libraries(dem_tool_ranks_tests PRIVATE tomodem_core nlohmann_json::nlohmann_json GTest::gtest_main
                      tomodem_test_paths)
target_compile_definitions(dem_tool_ranks_tests PRIVATE TOMODEM_MPIEXEC="${MPIEXEC_EXECUTABLE}")
add_dependencies(tomodem_mpi_tests dem_tool_ranks_tests tomodem-dem tomodem-sinter)
add_test(NAME dem_tool_ranks COMMAND dem_tool_ranks_tests)
set_tests_properties(dem_tool_ranks PROPERTIES LABELS mpi PROCESSORS 3
  ENVIRONMENT "OMP_NUM_THREADS=1;OMPI_MCA_mpi_yield_when_idle=1;OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")

# A bonded lattice pulled to failure: the same bonds break in the same steps on 1 to 4 ranks.
tomodem_mpi_test(dem_decomposition_bond_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_bonds_decomposed.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)

# Spheres falling onto a force-controlled floor, pressed by a moving lid: walls across ranks, 1-4 ranks, bitwise.
tomodem_mpi_test(dem_decomposition_wall_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_walls_decomposed.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)

# Checkpoints written on 2 ranks (HDF5 MPI-IO), restarted on 1-3 ranks and without mpirun:
# bitwise the uninterrupted run; another version refused (docs/dem.md, "Checkpoints").
add_executable(dem_checkpoint_ranks_tests ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_checkpoint_ranks.cpp)
target_link_libraries(dem_checkpoint_ranks_tests PRIVATE tomodem_core nlohmann_json::nlohmann_json GTest::gtest_main
                      tomodem_test_paths)
target_compile_definitions(dem_checkpoint_ranks_tests PRIVATE TOMODEM_MPIEXEC="${MPIEXEC_EXECUTABLE}")
add_dependencies(tomodem_mpi_tests dem_checkpoint_ranks_tests tomodem-dem)
add_test(NAME dem_checkpoint_ranks COMMAND dem_checkpoint_ranks_tests)
set_tests_properties(dem_checkpoint_ranks PROPERTIES LABELS mpi PROCESSORS 3
  ENVIRONMENT "OMP_NUM_THREADS=1;OMPI_MCA_mpi_yield_when_idle=1;OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")

# The energy budget (track_energy) across ranks: the falling column with local damping and a
# sheared periodic cell with Stokes drag, 1-4 ranks, terms to 1e-12 of the budget.
tomodem_mpi_test(dem_decomposition_energy_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_energy_decomposed.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)

# Checkpoints and restarts on ranks with bonds (breaking), walls and the energy budget, 1-4 ranks:
# the file equals the serial one and every restart ends bitwise on the uninterrupted serial run.
tomodem_mpi_test(dem_checkpoint_state_ranks_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_checkpoint_state_ranks.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)

# FIRE at a fixed cell on ranks: a disordered packing above jamming (frictionless and
# frictional) relaxes in the serial steps to the serial positions bitwise; enthalpy FIRE refused.
tomodem_mpi_test(dem_decomposition_fire_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_fire_decomposed.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)

# Free sintering of 256 spheres (the sintering driver's radius growth, mass scaling, densification
# and necks across ranks): 1-4 ranks against the serial driver, bit-identical on a fixed rank count.
tomodem_mpi_test(dem_decomposition_sinter_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/dem/test_sinter_decomposed.cpp
  LIBS tomodem_dem
  RANKS 1 2 3 4)
