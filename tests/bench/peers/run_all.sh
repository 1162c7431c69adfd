#!/bin/bash
# Every peer measurement of this folder in one go (about 30 minutes on one core, most of it Yade
# at N = 216000; QUICK=1: the small sizes only, a few minutes). Installs the Debian packages that
# are missing when run as root (lammps, lammps-examples, liggghts, yade, time). See README.md.
#
# env: OUT=<output folder> (default ./peers-out)  PIN="taskset -c 0"  QUICK=1
#      SCENE_NS, GAS_NS, BONDED_NS (sizes), WARM, STEPS
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
missing=""
for pkg in lammps lammps-examples liggghts yade time; do
  dpkg -s "$pkg" > /dev/null 2>&1 || missing="$missing $pkg"
done
if [ -n "$missing" ]; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $missing || exit 1
  else
    echo "run_all.sh: missing Debian packages:$missing (install them, or run as root)" >&2
    exit 1
  fi
fi
export OUT=${OUT:-$PWD/peers-out}
mkdir -p "$OUT/results" || exit 1
if [ "${QUICK:-0}" = 1 ]; then
  : "${SCENE_NS:=8000}" "${GAS_NS:=8788}" "${BONDED_NS:=10}"
fi
dpkg-query -W -f='${Package} ${Version}\n' lammps liggghts yade | tee "$OUT/results/versions.txt"
"$HERE/bench_sceneA.sh" ${SCENE_NS:-8000 64000 216000}
TAG=gas "$HERE/bench_sceneA.sh" ${GAS_NS:-8788 62500}
"$HERE/bench_bonded.sh" ${BONDED_NS:-10 20}
"$HERE/bench_restitution.sh"
"$HERE/bench_pour.sh"
# Yade's built-in quick benchmark (about 4400 spheres, linear visco-elastic law, gravity deposition)
( cd "$(mktemp -d)" && OMP_NUM_THREADS=1 ${PIN:-} yade -n -j1 --quickperformance 2>&1 |
    grep -E 'Performance|calculation velocity' ) | tee "$OUT/results/yade_quickperformance.txt"
echo "results in $OUT/results"
