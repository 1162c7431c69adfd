#!/usr/bin/env bash
# Configures and builds tomodem (Release) into ${BUILD_DIR:-build}.
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
# Native tuning (AVX2/FMA where the CPU has them) unless NATIVE=OFF: the binaries stay on this machine.
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTOMODEM_NATIVE="${NATIVE:-ON}" >/dev/null
cmake --build "$BUILD_DIR" -j "$JOBS"
