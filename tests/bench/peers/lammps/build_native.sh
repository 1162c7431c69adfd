#!/usr/bin/env bash
# Builds LAMMPS from Debian 12's own source package with the compiler and flags tomodem uses, so
# that speed is compared like with like (issue 19 item 4): both -O3 -DNDEBUG (CMake's Release)
# and, by default, -march=native. MARCH=x86-64 builds the generic pairing instead.
#
#   tests/bench/peers/lammps/build_native.sh [PREFIX]     # default PREFIX: build-lammps-native
#
# Needs a deb-src line for bookworm (see docs/benchmarks.md, "Peers built from source") and
# Debian's build tools (cmake, g++, ninja). Only the packages the benchmark scenes use are built:
# GRANULAR (pair gran/hertz/history, pair granular) and MOLECULE (bonds for the bonded scene).
# The executable is PREFIX/lmp; PREFIX/build-flags.txt records the compiler and flags.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../../.." && pwd)
prefix=$(realpath -m "${1:-$root/build-lammps-native}")
march=${MARCH:-native}
jobs=${JOBS:-2}
src="$prefix/src"
mkdir -p "$src"
if ! ls "$src"/lammps-*/cmake/CMakeLists.txt >/dev/null 2>&1; then
  if ! grep -rqs "^Types: deb-src\|^deb-src" /etc/apt/sources.list /etc/apt/sources.list.d/; then
    echo "build_native.sh: no deb-src line in /etc/apt/sources.list*; add one for bookworm main (see docs/benchmarks.md)" >&2
    exit 2
  fi
  (cd "$src" && apt-get source -q lammps >/dev/null)
fi
cml=$(ls "$src"/lammps-*/cmake/CMakeLists.txt 2>/dev/null | head -1)
[ -n "$cml" ] || { echo "build_native.sh: no LAMMPS source under $src (apt-get source failed?)" >&2; exit 1; }
lsrc=$(dirname "$(dirname "$cml")")
flags="-O3 -DNDEBUG -march=$march"
cmake -S "$lsrc/cmake" -B "$prefix/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS_RELEASE="$flags" -DCMAKE_C_FLAGS_RELEASE="$flags" \
  -DBUILD_MPI=ON -DBUILD_OMP=ON -DPKG_GRANULAR=ON -DPKG_MOLECULE=ON \
  -DWITH_JPEG=OFF -DWITH_PNG=OFF -DWITH_FFMPEG=OFF -DWITH_GZIP=OFF >/dev/null
cmake --build "$prefix/build" -j "$jobs" --target lmp
cp "$prefix/build/lmp" "$prefix/lmp"
{ echo "source: $(basename "$lsrc") (Debian 12 source package lammps)"
  echo "compiler: $(c++ --version | head -1)"
  echo "flags: $flags"; } > "$prefix/build-flags.txt"
cat "$prefix/build-flags.txt"
