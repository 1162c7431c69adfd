#!/usr/bin/env bash
# Sintering benchmark of issue 9 (docs/sintering.md): N monodisperse alumina spheres in a random
# green packing at relative density 0.60 (tomodem-pack, green.yaml), sintered freely to TARGET
# (tomodem-sinter, sinter.yaml) on THREADS threads. Prints one summary line and writes
# WORK/bench.json; exits 1 when the run misses the target or the two densities (overlaps counted
# once; rho0 V0/V from the cell) differ by more than 0.5 %.
#   run_sinter_bench.sh BIN_DIR [WORK_DIR]      env: N (20000), TARGET (0.80), THREADS (2)
# The green packing is kept in WORK (green_N.h5) and reused by later runs.
set -euo pipefail
bin=$(cd "${1:?usage: run_sinter_bench.sh BIN_DIR [WORK_DIR]}" && pwd)
work=${2:-$(mktemp -d -t tomodem-sinter-bench.XXXXXX)}
N=${N:-20000}
TARGET=${TARGET:-0.80}
THREADS=${THREADS:-2}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work"
cd "$work"
export OMP_WAIT_POLICY=PASSIVE

green=green_$N.h5
if [ ! -f "$green" ]; then
  /usr/bin/time -f "%e s wall, %M kB max RSS" -o pack_time.txt \
    "$bin/tomodem-pack" "$here/green.yaml" --particles "$N" --threads "$THREADS" --no-tessellation \
    -o "$green" --json "green_$N.json" -q > /dev/null
fi
sed -e "s/@GREEN@/$green/" -e "s/@TARGET@/$TARGET/" "$here/sinter.yaml" > sinter.yaml
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
/usr/bin/time -f "%e %M %U %S" -o sinter_time.txt \
  "$bin/tomodem-sinter" sinter.yaml --output-dir out --threads "$THREADS" --json summary.json -q > /dev/null
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

python3 - "$N" "$TARGET" "$THREADS" "$load_before" "$load_after" <<'PY'
import json, sys
n, target, threads, load0, load1 = sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
s = json.load(open("summary.json"))
wall, rss_kb, user, system = open("sinter_time.txt").read().split()[-4:]
g = json.load(open(f"green_{n}.json"))
rho, rho_cell = s["relative_density"], s["relative_density_cell"]
out = {
    "particles": s["n_particles"], "threads": threads, "green_solid_fraction": g.get("solid_fraction"),
    "green_coordination": g.get("coordination"),
    "initial_relative_density": s["initial_relative_density"], "relative_density": rho,
    "relative_density_cell": rho_cell, "density_mismatch": abs(rho - rho_cell) / rho,
    "mean_neck_ratio": s["mean_neck_ratio"], "neck_ratio": s.get("neck_ratio"),
    "coordination": s["coordination"], "shrinkage": s["shrinkage"], "steps": s["steps"],
    "sintering_time_s": s["sintering_time_s"], "temperature_K": s["temperature_K"],
    "shrinkage_max_deviation": max(abs(x / (sum(s["shrinkage"]) / 3) - 1) for x in s["shrinkage"]),
    "max_viscous_step_ratio": s.get("max_viscous_step_ratio"),
    "wall_time_s": s["wall_time_s"], "process_wall_s": float(wall), "cpu_time_s": float(user) + float(system),
    "max_rss_MB": int(rss_kb) / 1024,
    "loadavg_before": load0, "loadavg_after": load1, "stop_reason": s["stop_reason"],
}
json.dump(out, open("bench.json", "w"), indent=2)
print(f"N={out['particles']} rho {out['initial_relative_density']:.4f} -> {rho:.4f} (cell {rho_cell:.4f}), "
      f"{out['steps']} steps, {out['wall_time_s']:.1f} s wall ({out['cpu_time_s']:.1f} s CPU) on {threads} threads, "
      f"{out['max_rss_MB']:.0f} MB, a/R {out['mean_neck_ratio']:.3f}, Z {out['coordination']:.2f}, "
      f"shrinkage {', '.join(f'{x:.4f}' for x in out['shrinkage'])} (max deviation {out['shrinkage_max_deviation']:.4f}), "
      f"max dt*sum(eta)/m {out['max_viscous_step_ratio']:.3f}, load {load0} -> {load1}")
ok = s["stop_reason"] == "target_density" and rho >= target and out["density_mismatch"] < 0.005
sys.exit(0 if ok else 1)
PY
