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
# A python that can run the checks: pvpython first, then any python3 on PATH with h5py and numpy.
runner=()
if command -v pvpython >/dev/null 2>&1; then
  runner=(pvpython --force-offscreen-rendering)
else
  for py in $(type -ap python3); do
    if "$py" -c "import h5py, numpy" >/dev/null 2>&1; then runner=("$py"); break; fi
  done
fi
if [ ${#runner[@]} -eq 0 ]; then
  echo "overlay: skipped: neither pvpython nor a python3 with h5py and numpy"
  exit 77
fi
echo "overlay: checking with ${runner[*]}"
"${runner[@]}" "$here/overlay.py" "$work"
"${runner[@]}" "$here/check_outputs.py" "$work"
