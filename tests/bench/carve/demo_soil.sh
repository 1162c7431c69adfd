#!/bin/sh
# Demo of docs/carve.md: the macropores of the real soil sample (data/soil-sand-xct, 100³ voxels
# of 60.7 µm, tomodem-segment defaults) carved into a homogeneous packing of 40 µm spheres, with
# a short relaxation; writes docs/images/carve_soil_mid.png and prints the summary.
# Usage: tests/bench/carve/demo_soil.sh BUILD_DIR [WORK_DIR]
set -e
B=${1:?build dir}/bin
W=${2:-/tmp/tomodem_carve_demo}
R=$(cd "$(dirname "$0")/../../.." && pwd)
mkdir -p "$W"
export OMP_WAIT_POLICY=PASSIVE
"$B/tomodem-segment" "$R/data/soil-sand-xct/corner100.mhd" -q --threads 2 --vdb "$W/soil.vdb" -o "$W/labels.h5" --json "$W/segment.json"
cat > "$W/green.yaml" <<YAML
particles: ${TOMODEM_DEMO_PARTICLES:-40000}
seed: 1
phases:
  - name: alumina
    material: {youngs_modulus: 3.0e11, poisson_ratio: 0.22, density: 3950}
    size_distribution: {kind: lognormal, diameter: 4.0e-5, sigma: 0.15, basis: volume}
contact: {normal: hertz, friction: 0}
target: {solid_fraction: 0.55}
output: {packing: green.h5, tessellation: false}
YAML
"$B/tomodem-pack" "$W/green.yaml" -q --threads 2 -o "$W/green.h5" --json "$W/pack.json" --no-tessellation
"$B/tomodem-carve" "$W/green.h5" --level-set "$W/soil.vdb" --threads 2 --relax 200 -q \
  -o "$W/carved.h5" --json "$W/carved.json" --picture "$R/docs/images/carve_soil_mid.png"
"$B/tomodem-carve" "$W/green.h5" --labels "$W/labels.h5" --label-values 2 --threads 2 -q \
  -o "$W/carved_labels.h5" --json "$W/carved_labels.json"
cat "$W/carved.json"
grep -E '"macroporosity_(target|achieved)"' "$W/carved_labels.json"
