#!/usr/bin/env bash
# Installs the Debian 12 packages tomodem needs to build and test (idempotent; skips apt when
# everything is already there). Run as root or with sudo available.
set -euo pipefail
PKGS=(build-essential cmake ninja-build pkg-config git ccache
      libhdf5-dev hdf5-tools libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
      libfmt-dev libspdlog-dev libxxhash-dev
      libgtest-dev libgmock-dev libbenchmark-dev python3 gnuplot-nox
      libcgal-dev libgmp-dev libmpfr-dev
      libinsighttoolkit5-dev libopencv-imgproc-dev zlib1g-dev
      libopenvdb-dev libboost-iostreams-dev libtbb-dev libblosc-dev
      python3-h5py python3-openvdb
      libopenmpi-dev openmpi-bin petsc-dev libhdf5-openmpi-dev)
# python3-h5py and python3-openvdb (about 40 MB with numpy) run the overlay check of the outputs
# (tests/e2e/paraview) from the HDF5 files; python3-paraview (pvpython) runs it again through
# ParaView's own XDMF reader, and the pvpython snippet of docs/data-model.md. It is installed
# without recommends (measured, issue 21: 141 packages, 158 MB to fetch, 903 MB on disk, about
# 2.5 min); with them it pulls 194 packages, 1.0 GB. Debian 12's ParaView 5.11 renders only
# through GLX, so CI, headless, checks what ParaView reads, not a picture.
PV_PKGS=(python3-paraview)
# OpenCV imgproc draws the overlays and pictures; zlib writes them as PNG (libopencv-imgcodecs
# loads GDAL, poppler and ~140 libraries at every start of tomodem-segment and tomodem-carve).
# OpenMPI, PETSc and the parallel HDF5 build the MPI tests (-DTOMODEM_MPI=ON, ctest -L mpi, run by
# test.sh after the serial tests). libhdf5-openmpi-dev switches Debian's hdf5.pc alternative to
# the MPI library; the serial build is unaffected: it finds HDF5 through /usr/bin/h5cc (serial).
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  echo "installing: ${missing[*]}" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
for p in "${PV_PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
    echo "installing (no recommends): $p" >&2
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "$p" >/dev/null
  fi
done
