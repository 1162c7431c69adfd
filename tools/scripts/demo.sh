#!/usr/bin/env bash
# The README's main job: installs what is needed, builds (Release) and runs the demo on
# bundled data. Outputs go to ${OUT:-demo-out}/.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-demo-out}
mkdir -p "$OUT"
"$BUILD_DIR/bin/tomodem" dem pipelines/demo/settle.yaml --output-dir "$OUT" --json "$OUT/summary.json"
echo "demo outputs in $OUT/ (summary.json, packing .h5 + .xdmf for ParaView, time series .csv)"
