#!/usr/bin/env bash
# The README's test command: installs what is needed, builds (Release) and runs every test
# except the long benchmarks (ctest label `bench` runs only with BENCH=1).
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
EXCLUDE=(-LE bench); [ "${BENCH:-0}" = 1 ] && EXCLUDE=()
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" "${EXCLUDE[@]}"
