#!/bin/bash
# Image transport benchmark (docs/conduct.md, "Transport in a segmented image", Performance):
# tomodem-conduct --image on the solid phase of a segmented --kind pores phantom, axis x, two
# threads; CPU time (user + sys) and peak RSS from /usr/bin/time -v, the load average beside them.
# usage: tests/bench/conduct/image_bench.sh [BUILD]     (BUILD: build folder, default <repo>/build)
# env:   SIZES="128 256"  (512: 8.7 GB of memory, its volume from segment_gen_raw: SIZES="128 256 512")
#        WORK=<folder for the volumes> (default a temporary folder, removed at the end; KEEP=1 keeps it)
set -eu
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
BUILD=${1:-$REPO/build}
BIN=$BUILD/bin
SIZES=${SIZES:-"128 256"}
WORK_GIVEN=${WORK:-}
WORK=${WORK:-$(mktemp -d)}
export OMP_WAIT_POLICY=PASSIVE OMP_NUM_THREADS=2
for s in $SIZES; do
  if [ ! -f "$WORK/labels$s.h5" ] && [ "$s" -ge 512 ]; then
    # 512^3: the out-of-core benchmark's volume, as when docs/conduct.md's 512^3 row was measured
    # (tomodem-phantom then took hours at 512^3; it now takes 13 s, but the row is of this volume).
    "$BIN/segment_gen_raw" "$s" "$WORK/grey$s.raw"
    "$BIN/tomodem-segment" "$WORK/grey$s.raw" --raw-dims "$s,$s,$s" --raw-type uint16 --spacing 10um --threads 2 \
        -o "$WORK/labels$s.h5" -q --json "$WORK/made$s.json"
  elif [ ! -f "$WORK/labels$s.h5" ]; then
    "$BIN/tomodem-phantom" --kind pores --size "$s" -o "$WORK/grey$s.mha" -q --json "$WORK/made$s.json"
    "$BIN/tomodem-segment" "$WORK/grey$s.mha" --method intermeans -o "$WORK/labels$s.h5" -q --json "$WORK/made$s.json"
  fi
  echo "== $s^3  load: $(cut -d' ' -f1-3 /proc/loadavg)"
  /usr/bin/time -v "$BIN/tomodem-conduct" --image "$WORK/labels$s.h5" --phase 0 --axis x --threads 2 \
      --json "$WORK/conduct$s.json" -q 2> "$WORK/time$s.txt"
  grep -E "User time|System time|Elapsed|Maximum resident" "$WORK/time$s.txt"
  python3 - "$WORK/conduct$s.json" <<'PY'
import json, sys
a = json.load(open(sys.argv[1]))["axes"]["x"]; s = a["solver"]
print(f"unknowns {s['unknowns']}  iterations {s['iterations']}  levels {s['multigrid']['levels']}"
      f"  complexity {s['multigrid']['operator_complexity']:.2f}  set-up {s['setup_time_s']:.2f} s"
      f"  solve {s['solve_time_s']:.2f} s  sigma_eff {a['sigma_eff']:.6f}  tau {a['tortuosity']:.5f}"
      f"  error {a['sigma_eff_error']:.1e}  porosity {a['porosity']:.4f}")
PY
done
[ "${KEEP:-0}" = 1 ] || [ -n "$WORK_GIVEN" ] || rm -rf "$WORK"
