#!/bin/bash
# Scene A throughput of the peer codes: LAMMPS (pair granular and gran/hertz/history), LIGGGHTS
# and Yade, single-threaded, on identical initial states. See README.md.
#
# usage: bench_sceneA.sh [N ...]        (default 8000 64000 216000; gas: 8788 62500)
# env:   TAG=scene|gas  WARM=500  STEPS=2000  YADE_STEPS_LARGE=1000 (timed Yade steps for N >= 200000)
#        CODES="lammps liggghts yade"  OUT=<output folder>  PIN="taskset -c 0"
# out:   OUT/results/sceneA.csv (TAG=scene) or sceneA_gas.csv, logs in OUT/logs
set -u
source "$(dirname "$0")/common/lib.sh"
TAG=${TAG:-scene}
WARM=${WARM:-500}
STEPS=${STEPS:-2000}
YADE_STEPS_LARGE=${YADE_STEPS_LARGE:-1000}
CODES=${CODES:-lammps liggghts yade}
case $TAG in
  scene) NS=${*:-8000 64000 216000}; CSV=$OUT/results/sceneA.csv ;;
  gas) NS=${*:-8788 62500}; CSV=$OUT/results/sceneA_gas.csv ;;
  *) die "TAG must be scene or gas, not '$TAG'" ;;
esac
has() { [[ " $CODES " == *" $1 "* ]]; }
need python3 /usr/bin/time
has lammps && need lmp
has liggghts && need liggghts
has yade && need yade
[ -f "$CSV" ] || echo "code,version,model,N,warm_steps,timed_steps,loop_s,particle_steps_per_s,process_wall,peak_rss_MB,Z_end,KE_end_J,neighbor_builds,p_end_Pa" > "$CSV"

for N0 in $NS; do
  N=$(state "$TAG" "$N0") || exit 1
  if has lammps; then
    for style in granular hertzhist; do
      stem=$OUT/logs/${TAG}_lammps_${style}_N$N
      ( cd "$OUT" && timed "$stem" lmp -in "$PEERS/lammps/in.sceneA" -var N "$N" -var TAG "$TAG" -var STYLE $style \
          -var WARM "$WARM" -var STEPS "$STEPS" -var STATES "$OUT/states" -log "$stem.log" -screen none ) ||
        { echo "LAMMPS $style N=$N failed (see $stem.log)" >&2; continue; }
      loop=$(loop_time "$stem.log"); set -- $(last_thermo "$stem.log")
      [ $style = granular ] && model="pair granular hertz/material + mindlin + tsuji" || model="pair gran/hertz/history"
      echo "LAMMPS,$(version lammps),$model,$N,$WARM,$STEPS,$loop,$(rate "$N" "$STEPS" "$loop"),$(elapsed "$stem"),$(rss_mb "$stem"),$4,$3,$(builds "$stem.log"),$6" | tee -a "$CSV"
    done
  fi
  if has liggghts; then
    stem=$OUT/logs/${TAG}_liggghts_N$N
    if ( cd "$OUT" && timed "$stem" liggghts -in "$PEERS/liggghts/in.sceneA" -var N "$N" -var TAG "$TAG" \
        -var WARM "$WARM" -var STEPS "$STEPS" -var STATES "$OUT/states" -log "$stem.log" -screen none ); then
      loop=$(loop_time "$stem.log"); set -- $(last_thermo "$stem.log")
      echo "LIGGGHTS,$(version liggghts),gran model hertz tangential history,$N,$WARM,$STEPS,$loop,$(rate "$N" "$STEPS" "$loop"),$(elapsed "$stem"),$(rss_mb "$stem"),$4,$3,$(builds "$stem.log"),$6" | tee -a "$CSV"
    else
      echo "LIGGGHTS N=$N failed (see $stem.log)" >&2
    fi
  fi
  if has yade; then
    ysteps=$STEPS; [ "$N" -ge 200000 ] && ysteps=$YADE_STEPS_LARGE
    stem=$OUT/logs/${TAG}_yade_N$N
    ( cd "$OUT" && timed "$stem" yade -n -x -j1 "$PEERS/yade/sceneA.py" "$N" "$WARM" "$ysteps" -0.2 "$OUT/states" "$TAG" > "$stem.log" 2>&1 ) ||
      { echo "Yade N=$N failed (see $stem.log)" >&2; continue; }
    line=$(grep '^RESULT' "$stem.log")
    field() { echo "$line" | tr ' ' '\n' | awk -F= -v k="$1" '$1 == k {print $2}'; }
    loop=$(field wall)
    p=$(awk '/^PRESSURE/{sub("p=", "", $2); print $2}' "$stem.log")
    echo "Yade,$(version yade),FrictMat + MindlinPhys(en=es=0.5) + Law2_ScGeom_MindlinPhys_Mindlin,$N,$WARM,$ysteps,$loop,$(rate "$N" "$ysteps" "$loop"),$(elapsed "$stem"),$(rss_mb "$stem"),$(field Z),$(field KE),collider runs $(field collider_runs),$p" | tee -a "$CSV"
  fi
done
