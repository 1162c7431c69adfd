#!/bin/bash
# Measured inputs of the scaling model (docs/scaling.md), all in one run:
#   1. MPI costs on this machine: ping-pong, ring halo exchange and allreduce on 2 ranks
#      (tomodem-bench-mpi-pingpong of the MPI build);
#   2. the DEM cost per particle-step, scene A, one thread (tomodem-bench-sceneA, CPU time);
#   3. LAMMPS (Debian's lmp, MPI-enabled) on scene A with 1 and 2 MPI ranks, interleaved.
# Every line of every CSV carries the 1-minute load average at its start: timings taken on a
# machine whose load exceeds its cores are not results (say so where they are quoted).
#
# usage: tests/bench/mpi/run_scaling.sh
# env:   BUILD_MPI=<repo>/build-mpi  BUILD_BENCH=<repo>/build-bench  OUT=<repo>/build-mpi/scaling
#        N=8000 WARM=500 STEPS=2000 REPEATS=3 PINGPONG_REPEATS=7  MPIRUN=mpirun
# then:  python3 tests/bench/mpi/scaling_model.py OUT   (tables and the plot)
set -u
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
BUILD_MPI=${BUILD_MPI:-$REPO/build-mpi}
BUILD_BENCH=${BUILD_BENCH:-$REPO/build-bench}
OUT=${OUT:-$BUILD_MPI/scaling}
N=${N:-8000}
WARM=${WARM:-500}
STEPS=${STEPS:-2000}
REPEATS=${REPEATS:-3}
PINGPONG_REPEATS=${PINGPONG_REPEATS:-7}
MPIRUN=${MPIRUN:-mpirun}
# OpenMPI refuses to run as root without these (containers often run as root).
[ "$(id -u)" = 0 ] && export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$OUT"
source "$REPO/tests/bench/peers/common/lib.sh"   # state, timed, loop_time, rate; OMP_NUM_THREADS=1
need lmp /usr/bin/time python3
PINGPONG=$BUILD_MPI/bin/tomodem-bench-mpi-pingpong
BENCH=$BUILD_BENCH/bin/tomodem-bench-sceneA
[ -x "$PINGPONG" ] || die "missing $PINGPONG: configure with -DTOMODEM_MPI=ON and build tomodem-bench-mpi-pingpong"
[ -x "$BENCH" ] || die "missing $BENCH: build tomodem-bench-sceneA (tests/bench/run_bench.sh does)"
load() { cut -d' ' -f1 /proc/loadavg; }
cpu_s() { awk -F': ' '/User time/{u=$2} /System time/{s=$2} END{printf "%.3f", u + s}' "$1.time"; }

# 1. MPI costs
echo "load $(load)" > "$OUT/pingpong.load"
$MPIRUN -np 2 "$PINGPONG" --repeats "$PINGPONG_REPEATS" --csv "$OUT/pingpong.csv" || die "ping-pong failed"
echo "load $(load)" >> "$OUT/pingpong.load"

# 2 and 3, interleaved so that both see the same load
N=$(state scene "$N") || exit 1
CSV=$OUT/results/ranks.csv
echo "code,ranks,threads,repeat,N,timed_steps,loop_s,cpu_s,particle_steps_per_s,load1" > "$CSV"
for rep in $(seq 1 "$REPEATS"); do
  stem=$OUT/logs/tomodem_1t_r$rep
  l=$(load)
  timed "$stem" "$BENCH" "$OUT/states/scene_n$N.txt" --threads 1 --warm "$WARM" --steps "$STEPS" > "$stem.log" ||
    die "tomodem-bench-sceneA failed (see $stem.log)"
  loop=$(awk '/^loop_wall_s/{print $2}' "$stem.log"); cpu=$(awk '/^cpu_s/{print $2}' "$stem.log")
  echo "tomodem,1,1,$rep,$N,$STEPS,$loop,$cpu,$(rate "$N" "$STEPS" "$loop"),$l" >> "$CSV"
  for ranks in 1 2; do
    stem=$OUT/logs/lammps_np${ranks}_r$rep
    l=$(load)
    ( cd "$OUT" && timed "$stem" $MPIRUN -np "$ranks" lmp -in "$PEERS/lammps/in.sceneA" -var N "$N" -var TAG scene \
        -var STYLE granular -var WARM "$WARM" -var STEPS "$STEPS" -var STATES "$OUT/states" -log "$stem.log" \
        -screen none ) || die "LAMMPS on $ranks ranks failed (see $stem.log)"
    loop=$(loop_time "$stem.log")
    echo "lammps-granular,$ranks,1,$rep,$N,$STEPS,$loop,$(cpu_s "$stem"),$(rate "$N" "$STEPS" "$loop"),$l" >> "$CSV"
  done
done
cat "$CSV"
