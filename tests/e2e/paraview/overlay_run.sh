#!/usr/bin/env bash
# Makes a scan, its labels and level set (tomodem-phantom, tomodem-segment) and a packing of its
# grains carved by the level set (tomodem-carve), all in the scan's frame, then checks that they
# overlap (overlay.py); adds conduction fields, bonds and cracks, and checks that every XDMF sidecar
# and HDF5 output is viewable and states its unit and provenance (check_outputs.py).
# Usage: overlay_run.sh BIN_DIR WORK_DIR. Exit 77 (skipped) without pvpython and without h5py.
set -euo pipefail
bin=$1
work=$2
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work"
mkdir -p "$work"
cd "$work"
# 64^3 voxels of 10 um: three macropores in a fine-pored solid
"$bin/tomodem-phantom" --kind pores --size 64 --macropores 3 --seed 3 -o scan.mha --json phantom.json -q >/dev/null
"$bin/tomodem-segment" scan.mha -q --threads 2 --macropore-radius 4vox --grains --packing grains.h5 \
  -o labels.h5 --mha labels.mha --vdb pores.vdb --json segment.json
# The scan's box (voxel faces) as the image box, so the carve maps the image onto the packing as is.
"$bin/tomodem-carve" grains.h5 --level-set pores.vdb --image-box -5e-6 -5e-6 -5e-6 635e-6 635e-6 635e-6 \
  -o carved.h5 --json carve.json -q
# More viewable outputs for check_outputs.py: conduction fields of the labels, a bonded packing
# (one line per bond) and a fracture map (the cracks) of the shipped cathode powder.
"$bin/tomodem-conduct" --image labels.h5 --phase 0 -o fields.h5 --json conduct.json -q
"$bin/tomodem-bond" "$here/../../../data/examples/cathode.h5" -o bonded.h5 -q >/dev/null
"$bin/tomodem-fracture" bonded.h5 --fracture-energy 10 --stop-fraction 0.5 --no-elastic --map cracks.h5 \
  --json fracture.json -q >/dev/null
# The checks: through ParaView's XDMF reader when pvpython is installed (boxes only: headless CI
# has no OpenGL context for a picture), and from the HDF5 files with any python3 that has h5py
# and numpy; each that can run, runs. Skipped (77) when neither can.
h5py_python=""
for py in $(type -ap python3); do
  if "$py" -c "import h5py, numpy" >/dev/null 2>&1; then h5py_python=$py; break; fi
done
ran=0
if command -v pvpython >/dev/null 2>&1; then
  echo "overlay: checking with pvpython (ParaView's XDMF reader)"
  pvpython --force-offscreen-rendering "$here/overlay.py" "$work"
  ran=1
fi
if [ -n "$h5py_python" ]; then
  echo "overlay: checking with $h5py_python (h5py)"
  "$h5py_python" "$here/overlay.py" "$work" --h5py
  "$h5py_python" "$here/check_outputs.py" "$work"
  ran=1
fi
if [ $ran -eq 0 ]; then
  echo "overlay: skipped: neither pvpython nor a python3 with h5py and numpy"
  exit 77
fi
