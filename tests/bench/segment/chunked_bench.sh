#!/bin/sh
# Out-of-core tomodem-segment benchmark (issue 19 item 5; docs/segment.md "Volumes larger than
# memory", numbers in docs/benchmarks.md). ctest -L bench runs the 512^3 comparison with grains
# (bench_segment_chunked_grains512, each path three times, ~8 min, 1 GB of disk); 2048^3 is run
# by hand.
#
#   chunked_bench.sh BUILD_DIR WORK_DIR N MEMORY [compare]
#
# Writes an N^3 uint16 raw with segment_gen_raw (the bench_segment recipe, slab by slab), runs
# tomodem-segment --memory MEMORY under /usr/bin/time -v and, with "compare", the in-memory path
# on the same file and h5diff on /labels and /macropores (exit 1 if they differ). Prints CPU time
# (user + sys), peak RSS and the load. Deletes the volume and the label files at the end (the
# JSON summaries and time logs stay in WORK_DIR).
#   chunked_bench.sh build /tmp/seg 512 2GB compare     # identity at 512^3, ~1 GB disk
#   chunked_bench.sh build /tmp/seg 2048 8GB            # 16 GiB raw, ~75 GB free disk advised
# GRAINS=1: a volume of solid spheres (segment_gen_raw ... grains) segmented with --grains; the
# comparison then also counts the voxels whose /grains id differs (h5diff).
#   GRAINS=1 chunked_bench.sh build /tmp/seg 512 2GB compare
# THREADS (default 2) is --threads; REPEAT=3 runs each path three times and prints the median
# CPU, wall time and peak RSS after the single runs (the files of the last run are compared).
set -eu
[ $# -ge 4 ] || { echo "usage: $0 BUILD_DIR WORK_DIR N MEMORY [compare]" >&2; exit 2; }
B=$(cd "$1" && pwd)/bin
W=$2
N=$3
MEM=$4
CMP=${5:-}
mkdir -p "$W"
cd "$W"
export OMP_WAIT_POLICY=passive
T=${THREADS:-2}
report() {  # name of a /usr/bin/time -v log
  awk -v name="$1" '/User time/ {u=$4} /System time/ {s=$4} /Maximum resident/ {m=$6} /Elapsed/ {e=$8}
    END {printf "%s: cpu %.1f s (user %.1f + sys %.1f), peak RSS %.3f GB, wall %s\n", name, u+s, u, s, m*1024/1e9, e}' "$1"
}
R=${REPEAT:-1}
median() {  # the median of the CPU (s), wall (s) and peak RSS (GB) of the logs given
  for f in "$@"; do
    awk '/User time/ {u=$4} /System time/ {s=$4} /Maximum resident/ {m=$6}
      /Elapsed/ {n=split($8, t, ":"); w=0; for (i=1; i<=n; ++i) w=w*60+t[i]}
      END {printf "%.1f %.1f %.3f\n", u+s, w, m*1024/1e9}' "$f"
  done > median.txt
  k=$((($(wc -l < median.txt) + 1) / 2))
  col() { cut -d' ' -f"$1" median.txt | sort -n | sed -n "${k}p"; }
  echo "median of $#: cpu $(col 1) s, wall $(col 2) s, peak RSS $(col 3) GB"
  rm -f median.txt
}
timed() {  # NAME ARGS...: runs tomodem-segment REPEAT times, logs time_NAME.i.log
  name=$1
  shift
  i=1
  while [ $i -le "$R" ]; do
    /usr/bin/time -v "$B/tomodem-segment" "$@" 2> time_$name.$i.log
    report time_$name.$i.log
    i=$((i + 1))
  done
  [ "$R" -gt 1 ] && echo "$name: $(median time_$name.*.log)"
  return 0
}
echo "load before: $(cat /proc/loadavg)"
GRAINS=${GRAINS:-}
V=v$N.raw
if [ -n "$GRAINS" ]; then
  V=g$N.raw
  [ -f $V ] || "$B/segment_gen_raw" "$N" $V 1 grains
  COMMON="$V --raw-dims $N,$N,$N --raw-type uint16 --spacing 10um --threads $T -q --grains"
else
  [ -f $V ] || "$B/segment_gen_raw" "$N" $V
  COMMON="$V --raw-dims $N,$N,$N --raw-type uint16 --spacing 10um --threads $T -q"
fi
rm -f time_chunked$N.*.log time_memory$N.*.log
timed chunked$N $COMMON --memory "$MEM" -o chunked$N.h5 --json chunked$N.json
echo "load after chunked: $(cat /proc/loadavg)"
status=0
if [ "$CMP" = compare ]; then
  timed memory$N $COMMON -o memory$N.h5 --json memory$N.json
  echo "load after in-memory: $(cat /proc/loadavg)"
  if h5diff chunked$N.h5 memory$N.h5 /labels /labels && h5diff chunked$N.h5 memory$N.h5 /macropores /macropores; then
    echo "labels identical (/labels, /macropores)"
  else
    echo "LABELS DIFFER" >&2
    status=1
  fi
  if [ -n "$GRAINS" ]; then
    if h5diff -q chunked$N.h5 memory$N.h5 /grains /grains; then
      echo "grains identical (/grains)"
    else
      echo "GRAINS DIFFER: $(h5diff -r chunked$N.h5 memory$N.h5 /grains /grains | tail -1)" >&2
      status=1
    fi
  fi
  rm -f memory$N.h5 memory$N.xdmf
fi
rm -f $V chunked$N.h5 chunked$N.xdmf
exit $status
