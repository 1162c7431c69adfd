# tomodem-run starting `ranks:` steps through a real mpirun (docs/pipelines.md, "MPI steps").
# A plain test, not tomodem_mpi_test: the runner is no MPI program, and an mpirun started from
# inside an MPI rank is not allowed.
add_test(NAME mpi_runner_ranks_step
  COMMAND sh ${CMAKE_CURRENT_SOURCE_DIR}/runner_test.sh $<TARGET_FILE:tomodem-run>
          $<TARGET_FILE:tomodem-bench-mpi-pingpong>)
set_tests_properties(mpi_runner_ranks_step PROPERTIES LABELS mpi TIMEOUT 300 PROCESSORS 2
  PASS_REGULAR_EXPRESSION "OK: ranks: 2 ran through mpirun"
  ENVIRONMENT "TOMODEM_MPIRUN=mpirun --oversubscribe;OMP_NUM_THREADS=1;OMPI_MCA_mpi_yield_when_idle=1;OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1")
# tools/scripts/test.sh builds only tomodem_mpi_tests: the programs these tests start come with it.
add_dependencies(tomodem_mpi_tests tomodem-run)
if(TARGET tomodem-bench-mpi-pingpong)
  add_dependencies(tomodem_mpi_tests tomodem-bench-mpi-pingpong)
endif()
