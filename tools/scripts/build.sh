#!/usr/bin/env bash
# Configures and builds tomodem (Release) into ${BUILD_DIR:-build}; arguments go to CMake's
# configure step (-DTOMODEM_MPI=ON), BUILD_TARGET=name builds one target.
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
# A compiler cache where ccache is installed (install-deps.sh installs it; CCACHE=0 turns it off):
# a clean clone, as CI builds, then compiles only what changed since a build of this machine.
# ccache hashes the flag -march=native as text, not the CPU it stands for (ccache issue 824), so
# the cache is kept per set of target flags that -march=native means here. Paths under the
# checkout are hashed relative to it (CCACHE_BASEDIR), so two clones share their objects (the
# tests' absolute paths are compiled once per build tree: tests/test_paths.hpp). The settings
# travel in the launcher: a later `cmake --build` keeps them.
# ccache stops the compile when it cannot write its folder, so an unwritable one means no cache.
LAUNCHER=()
cpu=$({ c++ -march=native -Q --help=target 2>/dev/null || true; } | sha1sum | cut -c1-12)
cache_root=${XDG_CACHE_HOME:-${HOME:+$HOME/.cache}}  # neither set (HOME unset): no cache
dir=${CCACHE_DIR:-${cache_root:+$cache_root/tomodem-ccache/$cpu}}
if [ "${CCACHE:-1}" != 0 ] && [ -n "$dir" ] && command -v ccache >/dev/null && mkdir -p "$dir" 2>/dev/null \
  && [ -w "$dir" ]; then
  ccache="env;CCACHE_DIR=$dir;CCACHE_BASEDIR=$PWD;ccache"
  LAUNCHER=("-DCMAKE_CXX_COMPILER_LAUNCHER=$ccache" "-DCMAKE_C_COMPILER_LAUNCHER=$ccache")
else
  LAUNCHER=(-UCMAKE_CXX_COMPILER_LAUNCHER -UCMAKE_C_COMPILER_LAUNCHER)
fi
# Native tuning (AVX2/FMA where the CPU has them) unless NATIVE=OFF: the binaries stay on this machine.
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTOMODEM_NATIVE="${NATIVE:-ON}" "${LAUNCHER[@]}" \
  "$@" >/dev/null
cmake --build "$BUILD_DIR" -j "$JOBS" ${BUILD_TARGET:+--target "$BUILD_TARGET"}
