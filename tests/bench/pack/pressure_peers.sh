#!/bin/sh
# A jammed packing at a pressure target, tomodem-pack against Yade (issue 19 item 2; numbers in
# docs/benchmarks.md, "Packing to a pressure target", paragraph "Yade on the same spheres").
# Both codes start from the same spheres and stop at the same criterion (unbalanced-force ratio
# < 1e-4, the contact pressure within 1 % of the target), one thread each, one after the other.
#
#   pressure_peers.sh BUILD_DIR WORK_DIR N SEED [PRESSURE] [YADE_ARGS...]
#
# Runs the pressure-target bench input of criterion_sweep.py (Hertz alumina, lognormal sigma = 0.3
# by volume, d = 1 um, inserted at phi = 0.3) for N particles, SEED and PRESSURE. The common
# start is tomodem-pack's inserted spheres (a run stopped after its first step, exit 4), written
# as state_*.txt for Yade and state_*.data for LAMMPS (../peers/lammps/in.pressure_target shows
# why LAMMPS has no run). Then tomodem-pack runs to the target, and
# ../peers/yade/pressure_target.py (YADE_ARGS: its MAX_STEPS DAMPING STRAIN_PER_STEP SCALING
# CELL_MASS), each under /usr/bin/time -v. Prints one RESULT line per code and the load.
# Needs yade and python3 with h5py (Debian: yade, python3-h5py); exit 77 without yade.
set -eu
[ $# -ge 4 ] || { echo "usage: $0 BUILD_DIR WORK_DIR N SEED [PRESSURE] [YADE_ARGS...]" >&2; exit 2; }
B=$(cd "$1" && pwd)/bin
HERE=$(cd "$(dirname "$0")" && pwd)
W=$2
N=$3
SEED=$4
P=${5:-1.0e6}
[ $# -ge 5 ] && shift 5 || shift $#
command -v yade > /dev/null || { echo "pressure_peers.sh: yade not installed (Debian: apt-get install yade); skipped"; exit 77; }
mkdir -p "$W"
cd "$W"
export OMP_WAIT_POLICY=passive OMP_NUM_THREADS=1
PY=${PYTHON:-/usr/bin/python3}  # Debian's, with h5py
# The bench input as criterion_sweep.py writes it (one copy of it); N, SEED and PRESSURE as flags.
# Named per run (S), so runs of other N or seeds in the same WORK_DIR keep their own inputs.
S=n${N}_s$SEED
"$PY" -c "import sys; sys.path.insert(0, '$HERE'); import criterion_sweep; print(criterion_sweep.CONFIG.format(n=$N))" > pack_$S.yaml
{ cat pack_$S.yaml; echo "protocol: {max_steps: 1}"; } > start_$S.yaml
FLAGS="--seed $SEED --target-pressure $P --threads 1 -q"
# The common start: tomodem-pack's insertion (exit 4: stopped short of the target, by design).
"$B/tomodem-pack" start_$S.yaml -o start_$S.h5 $FLAGS --json start_$S.json 2> start_$S.log || [ $? -eq 4 ]
"$PY" - start_$S.h5 state_$S.txt <<'PY'
import sys
import h5py
with h5py.File(sys.argv[1], "r") as f:
    h = f["/cell/h"][()]
    x = f["/particles/position"][()]
    r = f["/particles/radius"][()]
assert abs(h[0][0] - h[1][1]) < 1e-12 * h[0][0] and abs(h[0][0] - h[2][2]) < 1e-12 * h[0][0], "cubic cell expected"
L = h[0][0]
with open(sys.argv[2], "w") as out:
    out.write("%.17g\n" % L)
    for p, ri in zip(x, r):
        out.write("%.17g %.17g %.17g %.17g\n" % (p[0] % L, p[1] % L, p[2] % L, 2 * ri))
# The same spheres for LAMMPS (../peers/lammps/in.pressure_target, which shows why it has no run).
with open(sys.argv[2][:-4] + ".data", "w") as out:
    out.write("tomodem-pack start\n\n%d atoms\n1 atom types\n" % len(r))
    out.write("".join("0 %.17g %s\n" % (L, a) for a in ("xlo xhi", "ylo yhi", "zlo zhi")))
    out.write("\nAtoms # sphere\n\n")
    for i, (p, ri) in enumerate(zip(x, r)):
        out.write("%d 1 %.17g 3950 %.17g %.17g %.17g\n" % (i + 1, 2 * ri, p[0] % L, p[1] % L, p[2] % L))
PY
echo "load before: $(cat /proc/loadavg)"
/usr/bin/time -v "$B/tomodem-pack" pack_$S.yaml -o pack_$S.h5 $FLAGS --json pack_$S.json 2> time_tomodem_$S.log
"$PY" - pack_$S.json time_tomodem_$S.log "$N" <<'PY'
import json, re, sys
r = json.load(open(sys.argv[1]))
t = open(sys.argv[2]).read()
cpu = float(re.search(r"User time \(seconds\): ([\d.]+)", t)[1]) + float(re.search(r"System time \(seconds\): ([\d.]+)", t)[1])
rss = float(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t)[1]) / 1024
print("RESULT code=tomodem n=%s steps=%d cpu=%.1f wall=%.1f phi=%.6f Z=%.3f p_over_P=%.5f unbalanced=%.3e reached=%d "
      "peak_rss_mb=%.0f" % (sys.argv[3], r["steps"], cpu, r["wall_time_s"], r["solid_fraction"], r["coordination"],
                            r["pressure"] / r["target_pressure"], r["unbalanced_force_ratio"], int(r["target_reached"]), rss))
PY
echo "load between: $(cat /proc/loadavg)"
/usr/bin/time -v yade -n -x -j1 "$HERE/../peers/yade/pressure_target.py" state_$S.txt "$P" "$@" > yade_$S.log 2> time_yade_$S.log
grep '^RESULT' yade_$S.log
echo "load after: $(cat /proc/loadavg)"
