# Shared helpers of the peer benchmark scripts (sourced, not run).
# Every script works on its own folder of inputs (PEERS, the folder above this file) and writes
# only under OUT: states/ (initial states), logs/ (LAMMPS/LIGGGHTS logs, Yade output, the
# `/usr/bin/time -v` reports) and results/ (CSV and text tables).

PEERS=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT=${OUT:-$PWD/peers-out}
PIN=${PIN:-}                  # e.g. PIN="taskset -c 0" to pin every run to one core
export OMP_NUM_THREADS=1      # all codes single-threaded, no MPI
mkdir -p "$OUT/states" "$OUT/logs" "$OUT/results" || exit 1
OUT=$(cd "$OUT" && pwd)

die() { echo "$(basename "$0"): $*" >&2; exit 1; }

# need EXE...: stop with a message naming the Debian packages when an executable is missing.
need() {
  local miss=""
  for exe in "$@"; do command -v "$exe" > /dev/null || miss="$miss $exe"; done
  [ -z "$miss" ] || die "missing:$miss (Debian packages: lammps -> lmp, liggghts, yade, time -> /usr/bin/time; see README.md)"
}

# version PACKAGE: the installed Debian version, or "unknown".
version() { dpkg-query -W -f='${Version}' "$1" 2> /dev/null || echo unknown; }

# state TAG N: make OUT/states/<TAG>_n<N>.{data,txt} when missing; prints the N actually used
# (scene: the nearest n^3, gas: the nearest 4 n^3).
state() {
  local tag=$1 N=$2 n
  if [ "$tag" = scene ]; then
    n=$(python3 -c "print(round($N ** (1 / 3)))"); N=$((n * n * n))
  else
    n=$(python3 -c "print(round(($N / 4) ** (1 / 3)))"); N=$((4 * n * n * n))
  fi
  [ -f "$OUT/states/${tag}_n$N.txt" ] || python3 "$PEERS/common/make_state.py" "$tag" "$n" "$OUT/states" > /dev/null ||
    die "could not write the $tag state for N=$N"
  echo "$N"
}

# timed LOG_STEM CMD...: run CMD under /usr/bin/time -v (report in LOG_STEM.time).
timed() { local stem=$1; shift; $PIN /usr/bin/time -v -o "$stem.time" "$@"; }
rss_mb() { awk -F: '/Maximum resident/{printf "%.1f", $2 / 1024}' "$1.time"; }
elapsed() { awk -F': ' '/Elapsed/{print $2}' "$1.time"; }

# LAMMPS/LIGGGHTS log helpers: the loop time of the last run, the last thermo line before it,
# the number of neighbour-list builds.
loop_time() { grep 'Loop time' "$1" | tail -1 | awk '{print $4}'; }
last_thermo() { grep -B1 'Loop time' "$1" | tail -2 | head -1; }
builds() { grep 'Neighbor list builds' "$1" | tail -1 | awk '{print $NF}'; }
# rate N STEPS SECONDS: particle-steps per second
rate() { python3 -c "print('%.4e' % ($1 * $2 / $3))"; }
