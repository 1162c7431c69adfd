#!/bin/sh
# Out-of-core tomodem-segment benchmark (issue 19 item 5; docs/segment.md "Volumes larger than
# memory", numbers in docs/benchmarks.md). ctest -L bench runs the 512^3 comparison with grains
# (bench_segment_chunked_grains512, ~4 min, 1 GB of disk); 2048^3 is run by hand.
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
/usr/bin/time -v "$B/tomodem-segment" $COMMON --memory "$MEM" -o chunked$N.h5 --json chunked$N.json 2> time_chunked$N.log
report time_chunked$N.log
echo "load after chunked: $(cat /proc/loadavg)"
status=0
if [ "$CMP" = compare ]; then
  /usr/bin/time -v "$B/tomodem-segment" $COMMON -o memory$N.h5 --json memory$N.json 2> time_memory$N.log
  report time_memory$N.log
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
