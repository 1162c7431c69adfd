#!/usr/bin/env bash
# The README's main job: installs what is needed, builds (Release) and runs the demo pipeline
# (pipelines/demo.yaml): the bundled soil scan through every tool to a results table, plots and
# an HTML report. Outputs go to ${OUT:-demo-out}/ (report: ${OUT:-demo-out}/report/index.html).
# Run it again and only what changed runs (nothing, when nothing did).
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-demo-out}
mkdir -p "$OUT"
# The pipeline's default is demo-out/; another folder is passed as a variable (absolute path).
SET=(); [ "$OUT" = demo-out ] || SET=(--set "out=$(cd "$OUT" && pwd)")
# OpenMP threads wait passively: steps run side by side on the cores.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
start=$(date +%s)
"$BUILD_DIR/bin/tomodem" run pipelines/demo.yaml --jobs "${JOBS:-$(nproc)}" "${SET[@]}" --json "$OUT/run.json"
echo "demo done in $(( $(date +%s) - start )) s: $OUT/report/index.html (table.csv, plots), step logs in pipelines/demo.logs/"
