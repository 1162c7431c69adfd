#!/usr/bin/env bash
# The README's test command: installs what is needed, builds (Release) and runs every test
# except the long benchmarks (ctest label `bench` runs only with BENCH=1); then the MPI tests
# (label `mpi`) in a second build with -DTOMODEM_MPI=ON.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
EXCLUDE=(-LE bench); [ "${BENCH:-0}" = 1 ] && EXCLUDE=()
# ctest runs tests side by side and several use two OpenMP threads (the DEM thread tests,
# Eigen's solvers): with more threads than cores, OpenMP's spinning barriers make a test up to
# 100x slower. Passive waiting costs the tests nothing (none of them measures time).
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
# ctest starts the tests it knows to be long first, from the times of its last run
# (Testing/Temporary/CTestCostData.txt). A clean clone has none, so ctest goes by test number and
# the demo (a fifth of the suite's time) started at test 989 of 1171, while the other core ran out
# of tests. Seed the longest tests' times (s, measured at load 9; only their order matters; a name
# that no longer exists is ignored) when there is no earlier run.
COSTS="$BUILD_DIR/Testing/Temporary/CTestCostData.txt"
if [ ! -f "$COSTS" ]; then
  mkdir -p "$(dirname "$COSTS")"
  printf '%s 1 %s\n' \
    Demo.SmallDemoRunsEveryToolThenNothingOnASecondRun 300 Pack.AggregatesStayBondedThroughPacking 91 \
    Voxel.BondedLatticeConvergesAndTheNetworkErrorIsMeasured 47 SegmentChunked.GrainsIdenticalToInMemory 46 \
    Voxel.CathodeSubVolumeConvergesWithAnObservedOrder 44 DemBadInput.EveryRowExits2NamingFileFieldAndValueAndWritesNothing 43 \
    PoreConcentration.CoarseGrainedEquatorStressAgainstGoodier 39 StudySmall.ReportIntervalsAdaptiveStopAndRankingsMatchTheReplicaTable 37 \
    Voxel.PointContactsVanishAsTheSquareRootOfTheVoxel 35 Voxel.SimpleCubicNeckLatticeConvergesAndHolmIsWithinModelError 34 \
    CgCompareImage.WorkedExampleOfTheDocsRunsAsWritten 32 Toughness.SlaKicIndependentOfCrackLength 27 \
    install_consumer 25 SinterSnapshots.OneRunWritesEachTargetDensityWithItsNecksAsBonds 24 install_man_pages 23 >"$COSTS"
  echo --- >>"$COSTS"
fi
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" "${EXCLUDE[@]}"

# The MPI build (docs/solvers.md, docs/scaling.md): same flags as build.sh plus TOMODEM_MPI, and
# only the MPI test executables (target tomodem_mpi_tests; a topic whose tests run tools adds
# them to that target). Each test runs under mpirun on 1, 2, ... ranks, oversubscribed, one
# OpenMP thread per rank.
MPI_BUILD_DIR=${MPI_BUILD_DIR:-build-mpi}
BUILD_DIR=$MPI_BUILD_DIR BUILD_TARGET=tomodem_mpi_tests bash tools/scripts/build.sh -DTOMODEM_MPI=ON
export OMP_NUM_THREADS=1
if [ "$(id -u)" -eq 0 ]; then export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1; fi
# -j: each MPI test declares its ranks (ctest PROCESSORS), so ctest pairs only one-rank tests and
# runs a test of 2 or more ranks alone (a PROCESSORS above -j takes every slot); the tests use
# their own per-process folders.
ctest --test-dir "$MPI_BUILD_DIR" --output-on-failure -j "$(nproc)" -L mpi
