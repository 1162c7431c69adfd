#!/bin/bash
# Scene A benchmark of issue 2, side by side with the peers in the same run:
# LAMMPS (pair granular and gran/hertz/history), LIGGGHTS and tomodem (1 thread, 2 threads, and
# the frictionless linear variant) on the dense periodic Hertz–Mindlin scene and its gas variant.
# Yade is skipped: it is 8–10× slower than the others (~4 min per run at N=64000) and would
# dominate the run; its figures are in docs/benchmarks.md ("Peer codes"), its inputs in
# tests/bench/peers (bench_sceneA.sh runs it).
#
# usage: tests/bench/run_bench.sh            (from anywhere; ~15 min on an idle 2-core machine)
# env:   NS="8000 64000"  VARIANTS="scene gas"  REPEATS=3  WARM=500  STEPS=2000
#        BUILD=<build dir with bin/tomodem-bench-sceneA> (default <repo>/build-bench, built if missing)
#        PEERS=<peer inputs> (default <repo>/tests/bench/peers)   PIN="taskset -c 0" (optional)
#        DOC=<markdown to update> (default <repo>/docs/benchmarks.md)   KEEP=1 keeps the temp folder
#        COMMIT=<label of the tomodem build> (default: the repository HEAD)
#        REPEATS_LARGE=<repeats for N >= 50000> (default REPEATS)   TMO=<seconds per single run, default 900>
#        CONFIGS="lammps-granular lammps-hertzhist liggghts tomodem-1t tomodem-2t tomodem-linear-frictionless-1t"
#        (default all; e.g. leave out tomodem-2t on a machine whose load exceeds its cores)
# Every cell is run REPEATS times, one after the other, codes interleaved; the table gives medians.
# Gas variant: N must be 4n³, so N=8000 → 8788 (n=13) and N=64000 → 62500 (n=25), as the peers.
set -u
REPO=$(cd "$(dirname "$0")/../.." && pwd)
NS=${NS:-"8000 64000"}
VARIANTS=${VARIANTS:-"scene gas"}
REPEATS=${REPEATS:-3}
REPEATS_LARGE=${REPEATS_LARGE:-$REPEATS}
TMO=${TMO:-900}
CONFIGS=${CONFIGS:-"lammps-granular lammps-hertzhist liggghts tomodem-1t tomodem-2t tomodem-linear-frictionless-1t"}
want() { [[ " $CONFIGS " == *" $1 "* ]]; }
WARM=${WARM:-500}
STEPS=${STEPS:-2000}
BUILD=${BUILD:-$REPO/build-bench}
PEERS=${PEERS:-$REPO/tests/bench/peers}
DOC=${DOC:-$REPO/docs/benchmarks.md}
PIN=${PIN:-}
export OMP_NUM_THREADS=1
# Passive waiting: an OpenMP thread that spins at a barrier takes a core from the other thread
# (or another job) on a shared machine, and the two-thread rows collapse 2-10x (issue 19).
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
BENCH=$BUILD/bin/tomodem-bench-sceneA

# ---- peers: install when missing (Debian packages; Yade deliberately not installed) ----
need=""
command -v lmp >/dev/null || need="$need lammps"
command -v liggghts >/dev/null || need="$need liggghts"
command -v python3 >/dev/null || need="$need python3"
[ -x /usr/bin/time ] || need="$need time"
if [ -n "$need" ]; then
  echo "installing:$need"
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends $need || {
    echo "error: could not install$need" >&2; exit 1; }
fi
if [ ! -x "$BENCH" ]; then
  bash "$REPO/tools/scripts/install-deps.sh" || exit 1
  cmake -S "$REPO" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTOMODEM_NATIVE="${NATIVE:-ON}" \
    -DTOMODEM_SKIP="network;pipeline;image;geometry;mechanics" &&
    cmake --build "$BUILD" --target tomodem-bench-sceneA -j2 || exit 1
fi

[ -f "$PEERS/lammps/in.sceneA" ] && [ -f "$PEERS/common/make_state.py" ] ||
  { echo "error: $PEERS does not hold the peer inputs (lammps/in.sceneA, common/make_state.py)" >&2; exit 2; }
TMP=$(mktemp -d /tmp/tomodem-bench.XXXXXX)
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$TMP"' EXIT
P=$TMP   # states/ (initial states) and logs/ of this run; the inputs stay in $PEERS
mkdir -p "$P/logs" "$P/states"
CSV=$TMP/runs.csv
echo "variant,N,code,config,repeat,loop_s,pps,rss_MB,pressure_Pa,Z,KE_J,rebuilds" > "$CSV"
LV=$(dpkg-query -W -f='${Version}' lammps); GV=$(dpkg-query -W -f='${Version}' liggghts)
LOAD0=$(cut -d' ' -f1-3 /proc/loadavg)
START=$(date -u +%Y-%m-%dT%H:%MZ)
echo "load average before: $LOAD0"

run_peer() {  # exe input variant N tag config log-prefix
  local exe=$1 dir=$2 variant=$3 N=$4 tag=$5 config=$6 rep=$7 extra=$8
  local log=$P/logs/${tag}_${config}_N${N}_r$rep
  ( cd "$P" && timeout "$TMO" $PIN /usr/bin/time -v -o "$log.time" $exe -in "$PEERS/$dir/in.sceneA" -var N "$N" -var TAG "$tag" $extra \
      -var WARM "$WARM" -var STEPS "$STEPS" -var STATES "$P/states" -log "$log.log" -screen none ) || { echo "  $config failed" >&2; return; }
  local loop last ke z pr nb rss pps
  loop=$(grep 'Loop time' "$log.log" | tail -1 | awk '{print $4}')
  last=$(grep -B1 'Loop time' "$log.log" | tail -2 | head -1)
  ke=$(echo $last | awk '{print $3}'); z=$(echo $last | awk '{print $4}'); pr=$(echo $last | awk '{print $6}')
  nb=$(grep 'Neighbor list builds' "$log.log" | tail -1 | awk '{print $NF}')
  rss=$(awk -F: '/Maximum resident/{printf "%.1f",$2/1024}' "$log.time")
  pps=$(python3 -c "print('%.4e'%($N*$STEPS/$loop))")
  echo "$variant,$N,$exe,$config,$rep,$loop,$pps,$rss,$pr,$z,$ke,$nb" | tee -a "$CSV"
}

run_tomodem() {  # variant N tag config rep threads law
  local variant=$1 N=$2 tag=$3 config=$4 rep=$5 threads=$6 law=$7
  local log=$P/logs/${tag}_${config}_N${N}_r$rep.txt pin=$PIN
  [ "$threads" -gt 1 ] && pin=""
  timeout "$TMO" $pin "$BENCH" "$P/states/${tag}_n$N.txt" --threads "$threads" --law "$law" --warm "$WARM" --steps "$STEPS" > "$log" ||
    { echo "  $config failed" >&2; return; }
  g() { awk -v k="$1" '$1==k{print $2}' "$log"; }
  echo "$variant,$N,tomodem,$config,$rep,$(g loop_wall_s),$(g particle_steps_per_second),$(g peak_rss_MB),$(g pressure_Pa),$(g coordination),$(g kinetic_energy_J),$(g neighbor_rebuilds)" | tee -a "$CSV"
}

for variant in $VARIANTS; do
  for N0 in $NS; do
    if [ "$variant" = scene ]; then
      n=$(python3 -c "print(round($N0**(1/3)))"); N=$((n * n * n)); tag=scene
      [ -f "$P/states/scene_n$N.txt" ] || python3 "$PEERS/common/make_state.py" scene $n "$P/states" > /dev/null || exit 1
    else
      n=$(python3 -c "print(round(($N0/4)**(1/3)))"); N=$((4 * n * n * n)); tag=gas
      [ -f "$P/states/gas_n$N.txt" ] || python3 "$PEERS/common/make_state.py" gas $n "$P/states" > /dev/null || exit 1
    fi
    reps=$REPEATS; [ "$N" -ge 50000 ] && reps=$REPEATS_LARGE
    for rep in $(seq 1 "$reps"); do
      echo "== $variant N=$N repeat $rep (load $(cut -d' ' -f1 /proc/loadavg))"
      want lammps-granular && run_peer lmp lammps "$variant" $N $tag lammps-granular $rep "-var STYLE granular"
      want lammps-hertzhist && run_peer lmp lammps "$variant" $N $tag lammps-hertzhist $rep "-var STYLE hertzhist"
      want liggghts && run_peer liggghts liggghts "$variant" $N $tag liggghts $rep ""
      want tomodem-1t && run_tomodem "$variant" $N $tag tomodem-1t $rep 1 hertz-mindlin
      want tomodem-2t && run_tomodem "$variant" $N $tag tomodem-2t $rep 2 hertz-mindlin
      want tomodem-linear-frictionless-1t &&
        run_tomodem "$variant" $N $tag tomodem-linear-frictionless-1t $rep 1 linear-frictionless
    done
  done
done
LOAD1=$(cut -d' ' -f1-3 /proc/loadavg)
echo "load average after: $LOAD1"

cp "$CSV" "$REPO/tests/bench/dem/last_run.csv"
python3 "$REPO/tests/bench/dem/summarize.py" "$CSV" "$DOC" \
  --meta "date=$START" "cpu=$(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2);print $2; exit}')" \
  "cores=$(getconf _NPROCESSORS_ONLN)" "native=$(grep -q "TOMODEM_NATIVE:BOOL=ON" "$BUILD/CMakeCache.txt" 2>/dev/null && echo "-march=native" || echo "no -march=native")" "kernel=$(uname -r)" "debian=$(cat /etc/debian_version)" "lammps=$LV" "liggghts=$GV" \
  "compiler=$(c++ --version | head -1)" "load_before=$LOAD0" "load_after=$LOAD1" "repeats=$REPEATS (N >= 50000: $REPEATS_LARGE)" \
  "warm=$WARM" "steps=$STEPS" "commit=${COMMIT:-$(git -C "$REPO" rev-parse --short HEAD)}" "pin=${PIN:-none}"
