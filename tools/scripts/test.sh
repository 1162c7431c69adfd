#!/usr/bin/env bash
# The README's test command: installs what is needed, builds (Release) and runs every test
# except the long benchmarks (ctest label `bench` runs only with BENCH=1).
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
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" "${EXCLUDE[@]}"
