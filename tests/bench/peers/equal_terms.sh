#!/bin/bash
# tomodem against LAMMPS and LIGGGHTS on equal terms (issue 19 item 4), in one interleaved run:
#
#   generic pairing: tomodem built for plain x86-64 (TOMODEM_NATIVE=OFF)  vs  Debian's lmp and
#                    liggghts binaries (generic x86-64 packages)
#   native pairing:  tomodem built -march=native (TOMODEM_NATIVE=ON)      vs  LAMMPS built from
#                    Debian's own source with -O3 -DNDEBUG -march=native (lammps/build_native.sh)
#
# on scene A dense (N = 8000, 64000), scene A gas (N = 8788, 62500) and the polydisperse 1:10
# dense scene (make_state.py poly; N = 19908). All single-threaded, OMP_WAIT_POLICY=PASSIVE,
# Hertz + Mindlin with history, the same state files, time step and step counts in every code.
# A generic tomodem binary takes its AVX2 + FMA force loop where the processor has it (the
# loop is compiled twice, kernels.cpp); the row "tomodem generic, baseline loop" forces the
# x86-64 baseline loop (TOMODEM_DEM_SIMD=baseline) to show what that choice is worth.
#
# usage: tests/bench/peers/equal_terms.sh            (about 8 min on a quiet 2-core machine)
# env:   REPEATS=3  OUT=<folder, default a temporary one, kept>  DOC_TABLE=<file for the markdown>
#        SCENES="dense gas poly"  GENERIC=<repo>/build-generic  NATIVE=<repo>/build-bench
#        LMP_NATIVE=<repo>/build-lammps-native/lmp  BASELINE=1 (also time the baseline loop)
#        CLI_BUILD=<repo>/build (the build whose bin/tomodem-dem is measured; any configuration:
#        memory does not depend on the flags)
#        BUILD=0 (do not build; use the binaries as they are)  QUICK=1 (a tenth of the steps: a
#        check that everything runs, not a measurement)
# out:   OUT/runs.csv (every run), OUT/table.md (the tables for docs/benchmarks.md), printed too.
#
# Speed is N × timed steps / the loop's wall time (LAMMPS/LIGGGHTS "Loop time", tomodem
# steady_clock around the timed run), each code alone on the machine in turn; the ratio of every
# repeat is printed (tomodem / the fastest peer of its pairing in the same repeat) and the table
# gives medians. Memory: peak RSS per particle of the CLI (tomodem-dem on scene A at two sizes,
# as users run it, with its default outputs) and of LAMMPS, marginal: (RSS(N2) − RSS(N1)) / (N2 − N1).
set -u
export LC_ALL=C OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE
HERE=$(cd "$(dirname "$0")" && pwd)
REPO=$(cd "$HERE/../../.." && pwd)
REPEATS=${REPEATS:-3}
SCENES=${SCENES:-dense gas poly}
GENERIC=${GENERIC:-$REPO/build-generic}
NATIVE=${NATIVE:-$REPO/build-bench}
LMP_NATIVE=${LMP_NATIVE:-$REPO/build-lammps-native/lmp}
CLI_BUILD=${CLI_BUILD:-$REPO/build}
BASELINE=${BASELINE:-1}
OUT=${OUT:-$(mktemp -d /tmp/tomodem-equal.XXXXXX)}
mkdir -p "$OUT/states" "$OUT/logs" || exit 1
OUT=$(cd "$OUT" && pwd)
die() { echo "equal_terms.sh: $*" >&2; exit 1; }

# ---- steps per scene: sized so that the whole run takes ~8 min on a quiet 2-core machine ----
# scene N0 warm timed dt skin neigh
CASES=""
for s in $SCENES; do
  case $s in
    dense) CASES="$CASES dense:scene:8000:200:1500:1.35e-6:2.0e-4:bin dense:scene:64000:100:400:1.35e-6:2.0e-4:bin" ;;
    gas) CASES="$CASES gas:gas:8788:200:2000:1.35e-6:2.0e-4:bin gas:gas:62500:100:600:1.35e-6:2.0e-4:bin" ;;
    # 1:10: time step 0.1 Rayleigh time of the small spheres, skin 0.2 of their diameter.
    poly) CASES="$CASES poly:poly:19908:100:500:1.35e-7:2.0e-5:multi" ;;
    *) die "unknown scene '$s' (dense, gas, poly)" ;;
  esac
done

# ---- executables ----
command -v lmp > /dev/null || die "Debian's lmp is missing (apt-get install lammps)"
[ -x /usr/bin/time ] || die "/usr/bin/time is missing (apt-get install time)"
HAVE_LIGGGHTS=0; command -v liggghts > /dev/null && HAVE_LIGGGHTS=1
[ -x "$LMP_NATIVE" ] || die "$LMP_NATIVE is missing: run tests/bench/peers/lammps/build_native.sh first"
build() {  # dir native target...
  local dir=$1 native=$2 lock=""
  shift 2
  command -v flock > /dev/null && lock="flock /tmp/tomodem-build.lock"
  if [ ! -f "$dir/CMakeCache.txt" ]; then
    cmake -S "$REPO" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTOMODEM_NATIVE="$native" \
      -DTOMODEM_SKIP="network;pipeline;image;geometry;mechanics" > "$OUT/logs/configure_$native.log" ||
      die "configure of $dir failed (see $OUT/logs/configure_$native.log)"
  fi
  [ "$native" = any ] || grep -q "TOMODEM_NATIVE:BOOL=$native" "$dir/CMakeCache.txt" ||
    die "$dir is not configured with TOMODEM_NATIVE=$native"
  $lock cmake --build "$dir" -j2 --target "$@" > "$OUT/logs/build_$(basename "$dir").log" ||
    die "build in $dir failed (see $OUT/logs/build_$(basename "$dir").log)"
}
if [ "${BUILD:-1}" = 1 ]; then
  build "$GENERIC" OFF tomodem-bench-sceneA
  build "$NATIVE" ON tomodem-bench-sceneA
  [ -f "$CLI_BUILD/CMakeCache.txt" ] || die "$CLI_BUILD is not a configured build (for tomodem-dem)"
  build "$CLI_BUILD" any tomodem-dem
fi
for b in "$GENERIC/bin/tomodem-bench-sceneA" "$NATIVE/bin/tomodem-bench-sceneA" "$CLI_BUILD/bin/tomodem-dem"; do
  [ -x "$b" ] || die "$b is missing"
done

flags_of() {  # build dir -> the compile flags of libs/dem
  awk -F= '/^CMAKE_CXX_FLAGS_RELEASE:/{r=$2} /^TOMODEM_NATIVE:BOOL=ON/{n=" -march=native"} END{print r " -fno-math-errno" n}' "$1/CMakeCache.txt"
}
GFLAGS="$(flags_of "$GENERIC"), AVX2+FMA force loop at run time"
NFLAGS=$(flags_of "$NATIVE")
LNFLAGS=$(awk -F': ' '/^flags/{print $2}' "$(dirname "$LMP_NATIVE")/build-flags.txt" 2> /dev/null)
DEBFLAGS="Debian package $(dpkg-query -W -f='${Version}' lammps 2> /dev/null) (dpkg-buildflags: $(dpkg-buildflags --get CXXFLAGS 2> /dev/null | awk '{print $1, $2}'), generic x86-64)"
LIGFLAGS="Debian package $(dpkg-query -W -f='${Version}' liggghts 2> /dev/null) (generic x86-64)"
CPU=$(lscpu | awk -F: '/Model name/{gsub(/^ +/, "", $2); print $2; exit}')
AVX2=$(grep -qw avx2 /proc/cpuinfo && echo yes || echo no)
LOAD0=$(cut -d' ' -f1-3 /proc/loadavg)
START=$(date -u +%Y-%m-%dT%H:%MZ)
COMMIT=$(git -C "$REPO" rev-parse --short HEAD 2> /dev/null || echo unknown)
echo "equal_terms: $START, $CPU ($(getconf _NPROCESSORS_ONLN) cores, AVX2 $AVX2), commit $COMMIT, load before $LOAD0, output $OUT"

# ---- one run of each code ----
CSV=$OUT/runs.csv
echo "scene,N,config,repeat,loop_s,pps,rss_MB,p_Pa,Z,KE_trans_J,KE_rot_J,rebuilds,load1" > "$CSV"

state() {  # tag N0 -> N
  local tag=$1 N0=$2 n N
  case $tag in
    scene) n=$(python3 -c "print(round($N0 ** (1 / 3)))"); N=$((n * n * n)) ;;
    gas) n=$(python3 -c "print(round(($N0 / 4) ** (1 / 3)))"); N=$((4 * n * n * n)) ;;
    poly) n=$(python3 -c "print(round(($N0 / 311) ** (1 / 3)))")   # about 311 spheres per large one
          [ -f "$OUT/states/poly_cells$n" ] ||
            python3 "$HERE/common/make_state.py" poly "$n" "$OUT/states" | sed -n 's/.*_n\([0-9]*\):.*/\1/p' > "$OUT/states/poly_cells$n"
          N=$(cat "$OUT/states/poly_cells$n") ;;
  esac
  [ -f "$OUT/states/${tag}_n$N.txt" ] || python3 "$HERE/common/make_state.py" "$tag" "$n" "$OUT/states" > /dev/null ||
    die "could not write the $tag state"
  echo "$N"
}

peer() {  # exe input config scene tag N rep warm steps dt skin neigh
  local exe=$1 input=$2 config=$3 scene=$4 tag=$5 N=$6 rep=$7 warm=$8 steps=$9 dt=${10} skin=${11} neigh=${12}
  local log=$OUT/logs/${scene}_${config}_N${N}_r$rep extra=""
  [ "$config" = liggghts ] && [ "$tag" = poly ] && { extra="-var NT 2"; neigh=bin; }  # LIGGGHTS 3.8's multi finds no contacts here
  [ "$input" = lammps ] && extra="-var STYLE hertzhist"
  ( cd "$OUT" && /usr/bin/time -v -o "$log.time" "$exe" -in "$HERE/$input/in.sceneA" -var N "$N" -var TAG "$tag" $extra \
      -var WARM "$warm" -var STEPS "$steps" -var STATES "$OUT/states" -var DT "$dt" -var SKIN "$skin" -var NEIGH "$neigh" \
      -log "$log.log" -screen none ) || { echo "  $config failed (see $log.log)" >&2; return; }
  local loop last rss nb
  loop=$(grep 'Loop time' "$log.log" | tail -1 | awk '{print $4}')
  last=$(grep -B1 'Loop time' "$log.log" | tail -2 | head -1)
  nb=$(grep 'Neighbor list builds' "$log.log" | tail -1 | awk '{print $NF}')
  rss=$(awk -F: '/Maximum resident/{printf "%.1f", $2 / 1024}' "$log.time")
  set -- $last
  echo "$scene,$N,$config,$rep,$loop,$(python3 -c "print('%.4e' % ($N * $steps / $loop))"),$rss,$6,$4,$3,$7,$nb,$(cut -d' ' -f1 /proc/loadavg)" >> "$CSV"
}

tomodem() {  # build config scene tag N rep warm steps dt skin [env]
  local bin=$1/bin/tomodem-bench-sceneA config=$2 scene=$3 tag=$4 N=$5 rep=$6 warm=$7 steps=$8 dt=$9 skin=${10} envs=${11:-}
  local log=$OUT/logs/${scene}_${config}_N${N}_r$rep.txt
  env $envs "$bin" "$OUT/states/${tag}_n$N.txt" --warm "$warm" --steps "$steps" --dt "$dt" --skin "$skin" > "$log" 2>&1 ||
    { echo "  $config failed (see $log)" >&2; return; }
  g() { awk -v k="$1" '$1 == k {print $2}' "$log"; }
  echo "$scene,$N,$config,$rep,$(g loop_wall_s),$(g particle_steps_per_second),$(g peak_rss_MB),$(g pressure_Pa),$(g coordination),$(g ke_translational_J),$(g ke_rotational_J),$(g neighbor_rebuilds),$(cut -d' ' -f1 /proc/loadavg)" >> "$CSV"
}

# ---- the interleaved run: every repeat runs every code on every case, one after the other ----
for rep in $(seq 1 "$REPEATS"); do
  for c in $CASES; do
    IFS=: read -r scene tag N0 warm steps dt skin neigh <<< "$c"
    [ "${QUICK:-0}" = 1 ] && warm=$((warm / 10)) steps=$((steps / 10))
    N=$(state "$tag" "$N0") || exit 1
    echo "== repeat $rep: $scene N=$N (load $(cut -d' ' -f1-3 /proc/loadavg))"
    peer lmp lammps lammps-debian "$scene" "$tag" "$N" "$rep" "$warm" "$steps" "$dt" "$skin" "$neigh"
    [ $HAVE_LIGGGHTS = 1 ] && peer liggghts liggghts liggghts "$scene" "$tag" "$N" "$rep" "$warm" "$steps" "$dt" "$skin" "$neigh"
    tomodem "$GENERIC" tomodem-generic "$scene" "$tag" "$N" "$rep" "$warm" "$steps" "$dt" "$skin"
    [ "$BASELINE" = 1 ] && tomodem "$GENERIC" tomodem-generic-baseline "$scene" "$tag" "$N" "$rep" "$warm" "$steps" "$dt" "$skin" TOMODEM_DEM_SIMD=baseline
    peer "$LMP_NATIVE" lammps lammps-native "$scene" "$tag" "$N" "$rep" "$warm" "$steps" "$dt" "$skin" "$neigh"
    tomodem "$NATIVE" tomodem-native "$scene" "$tag" "$N" "$rep" "$warm" "$steps" "$dt" "$skin"
    python3 - "$CSV" "$scene" "$N" "$rep" << 'EOF'
import csv, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r['scene'] == sys.argv[2] and r['N'] == sys.argv[3] and r['repeat'] == sys.argv[4]]
pps = {r['config']: float(r['pps']) for r in rows if r['pps']}
def ratio(t, peers):
    best = max((pps[p] for p in peers if p in pps), default=0)
    return '%.2f' % (pps[t] / best) if t in pps and best else 'n/a'
print('   ' + '  '.join('%s %.3e' % kv for kv in pps.items()))
print('   ratios: generic %s (baseline loop %s), native %s' % (ratio('tomodem-generic', ['lammps-debian', 'liggghts']),
      ratio('tomodem-generic-baseline', ['lammps-debian', 'liggghts']), ratio('tomodem-native', ['lammps-native'])))
EOF
  done
done

# ---- memory per particle of the CLI (tomodem-dem, scene A as in docs/dem.md, default outputs) ----
# Gas: scene A-gas as the CLI generates it (FCC at solid fraction 0.55, velocities up to 1 m/s;
# N = 4 cells³, 8788 and 62 500 as in the tables).
cli_rss() {  # dense|gas cells -> peak RSS MB
  local n=$2 d=$OUT/cli_$1_$2 gen
  case $1 in
    dense) gen="arrangement: simple_cubic, cells: $n, radius: 0.5e-3, spacing: 0.9837e-3, jitter: 0.015, velocity: 0.1" ;;
    gas) gen="arrangement: fcc, cells: $n, radius: 0.5e-3, solid_fraction: 0.55, velocity: 1.0" ;;
  esac
  mkdir -p "$d"
  cat > "$d/scene.yaml" << EOF
materials:
  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}
particles:
  generate: {$gen, seed: 3, phase: glass}
physics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}
protocol: {timestep: 1.35e-6, steps: 300}
settings: {skin: 2.0e-4}
output: {packing: out.h5, series: series.csv}
EOF
  /usr/bin/time -v -o "$d/time.txt" "$CLI_BUILD/bin/tomodem-dem" "$d/scene.yaml" --output-dir "$d/out" --json "$d/out/summary.json" \
    > "$d/log.txt" 2>&1 || { echo "  tomodem-dem $1 cells $n failed (see $d/log.txt)" >&2; echo 0; return; }
  awk -F: '/Maximum resident/{printf "%.1f", $2 / 1024}' "$d/time.txt"
}
echo "== CLI memory (tomodem-dem, 300 steps)"
CLI1=$(cli_rss dense 20); CLI2=$(cli_rss dense 40); GAS1=$(cli_rss gas 13); GAS2=$(cli_rss gas 25)
echo "   tomodem-dem peak RSS: dense N=8000 $CLI1 MB, N=64000 $CLI2 MB; gas N=8788 $GAS1 MB, N=62500 $GAS2 MB"
LOAD1=$(cut -d' ' -f1-3 /proc/loadavg)
echo "load after $LOAD1"

# ---- tables ----
python3 - "$CSV" "$OUT/table.md" "$CLI1" "$CLI2" "$GAS1" "$GAS2" << EOF
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
cli1, cli2, gas1, gas2 = (float(a) for a in sys.argv[3:7])
flags = {'lammps-debian': "$DEBFLAGS", 'liggghts': "$LIGFLAGS", 'tomodem-generic': "$GFLAGS",
         'tomodem-generic-baseline': "$GFLAGS".split(',')[0] + ', baseline x86-64 loop (TOMODEM_DEM_SIMD=baseline)',
         'lammps-native': "LAMMPS from Debian's source, $LNFLAGS", 'tomodem-native': "$NFLAGS"}
names = {'lammps-debian': 'LAMMPS gran/hertz/history', 'liggghts': 'LIGGGHTS hertz + history',
         'tomodem-generic': '**tomodem** generic', 'tomodem-generic-baseline': 'tomodem generic, baseline loop',
         'lammps-native': 'LAMMPS gran/hertz/history', 'tomodem-native': '**tomodem** native'}
pairings = [('generic', ['lammps-debian', 'liggghts'], ['tomodem-generic', 'tomodem-generic-baseline']),
            ('native', ['lammps-native'], ['tomodem-native'])]
cases = []
for r in rows:
    if (r['scene'], r['N']) not in cases: cases.append((r['scene'], r['N']))
def med(xs): return statistics.median(xs) if xs else float('nan')
out = []
out.append('Run %s, %s, commit %s; load average before %s, after %s (1/5/15 min); medians of $REPEATS repeats, codes interleaved, one thread each, OMP_WAIT_POLICY=PASSIVE; AVX2 on this CPU: $AVX2.' % ("$START", "$CPU", "$COMMIT", "$LOAD0", "$LOAD1"))
out.append('')
for pname, peers, toms in pairings:
    out.append('**%s pairing** (ratio: tomodem / the fastest peer of the pairing, per repeat, then the median)' % pname)
    out.append('')
    out.append('| scene | N | code | build flags | particle-steps/s | ratio (per repeat) | KE trans J | KE rot J | Z | p Pa | rebuilds | peak RSS MB |')
    out.append('|---|---|---|---|---|---|---|---|---|---|---|---|')
    for scene, N in cases:
        sel = [r for r in rows if r['scene'] == scene and r['N'] == N]
        reps = sorted({r['repeat'] for r in sel})
        best = {}
        for rep in reps:
            b = [float(r['pps']) for r in sel if r['repeat'] == rep and r['config'] in peers and r['pps']]
            if b: best[rep] = max(b)
        for cfg in peers + toms:
            rr = [r for r in sel if r['config'] == cfg and r['pps']]
            if not rr: continue
            pps = med([float(r['pps']) for r in rr])
            if cfg in toms:
                per = [float(r['pps']) / best[r['repeat']] for r in rr if r['repeat'] in best]
                ratio = '**%.2f** (%s)' % (med(per), ', '.join('%.2f' % x for x in per))
            else:
                per = [float(r['pps']) / best[r['repeat']] for r in rr if r['repeat'] in best]
                ratio = '%.2f' % med(per)
            def m(k):
                v = [float(r[k]) for r in rr if r[k] not in ('', None)]
                return med(v)
            out.append('| %s | %s | %s | %s | %.3e | %s | %.3e | %.3e | %.2f | %.4g | %.0f | %.1f |' % (
                scene, N, names[cfg], flags[cfg], pps, ratio, m('KE_trans_J'), m('KE_rot_J'), m('Z'), m('p_Pa'), m('rebuilds'), m('rss_MB')))
    out.append('')
# memory per particle, marginal between the two dense sizes
dense = sorted({int(N) for s, N in cases if s == 'dense'})
out.append('**Memory per particle** (peak RSS, marginal between N = 8000 and 64000 of the dense scene; the CLI with its default outputs, 300 steps)')
out.append('')
out.append('| code | RSS N=8000 MB | RSS N=64000 MB | marginal kB/particle |')
out.append('|---|---|---|---|')
if cli1 > 0 and cli2 > 0:
    out.append('| **tomodem-dem** (CLI) | %.1f | %.1f | **%.3f** |' % (cli1, cli2, (cli2 - cli1) * 1024 / 56000))
if len(dense) == 2:
    for cfg in ['lammps-debian', 'liggghts', 'lammps-native', 'tomodem-generic', 'tomodem-native']:
        a = [float(r['rss_MB']) for r in rows if r['scene'] == 'dense' and int(r['N']) == dense[0] and r['config'] == cfg and r['rss_MB']]
        b = [float(r['rss_MB']) for r in rows if r['scene'] == 'dense' and int(r['N']) == dense[1] and r['config'] == cfg and r['rss_MB']]
        if a and b:
            label = names[cfg] + (' (bench binary)' if cfg.startswith('tomodem') else '') + (' native' if cfg == 'lammps-native' else '')
            out.append('| %s | %.1f | %.1f | %.3f |' % (label, med(a), med(b), (med(b) - med(a)) * 1024 / (dense[1] - dense[0])))
if gas1 > 0 and gas2 > 0:
    out.append('| **tomodem-dem** (CLI), gas N = 8788 / 62 500 | %.1f | %.1f | **%.3f** |' % (gas1, gas2, (gas2 - gas1) * 1024 / 53712))
out.append('')
out.append('(kB here = 1024 bytes, RSS in MiB as /usr/bin/time and VmHWM report it, as in the tables above.)')
open(sys.argv[2], 'w').write('\n'.join(out) + '\n')
print('\n'.join(out))
EOF
echo "equal_terms: CSV $CSV, table $OUT/table.md"
[ -n "${DOC_TABLE:-}" ] && cp "$OUT/table.md" "$DOC_TABLE"
exit 0
