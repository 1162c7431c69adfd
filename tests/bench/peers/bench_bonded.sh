#!/bin/bash
# Bonded simple cubic lattice in slow tension: Yade (cohesive bonds with moments) and LAMMPS
# (harmonic bonds, central springs only). E against the analytic kn/(2R) = 5e7 Pa. See README.md.
#
# usage: bench_bonded.sh [n ...]        (lattice edge in spheres; default 10 20)
# env:   CODES="yade lammps"  OUT=<output folder>  PIN="taskset -c 0"
# out:   OUT/results/bonded.csv, the stress-strain curves and logs in OUT/logs
set -u
source "$(dirname "$0")/common/lib.sh"
CODES=${CODES:-yade lammps}
has() { [[ " $CODES " == *" $1 "* ]]; }
need python3 /usr/bin/time
has lammps && need lmp
has yade && need yade
CSV=$OUT/results/bonded.csv
E_ANA=5e7
[ -f "$CSV" ] || echo "code,version,bonds,n,N,bond_count,steps,loop_s,process_wall,peak_rss_MB,E_ana_Pa,E_pulled_Pa,ratio_pulled,E_fixed_Pa,ratio_fixed" > "$CSV"
kv() { echo "$2" | tr ' ' '\n' | awk -F= -v k="$1" '$1 == k {print $2}'; }

for n in ${*:-10 20}; do
  N=$((n * n * n)); nb=$((3 * n * n * (n - 1)))
  if has yade; then
    stem=$OUT/logs/bonded_yade_n$n
    if ( cd "$OUT/logs" && timed "$stem" yade -n -x -j1 "$PEERS/yade/bonded_tension.py" "$n" > "$stem.log" 2>&1 ); then
      r=$(grep '^RESULT' "$stem.log")
      fit=$(python3 "$PEERS/common/fit_modulus.py" "$OUT/logs/bonded_yade_n$n.dat" $E_ANA)
      echo "Yade,$(version yade),CohFrictMat/CohFrictPhys (kn = young R) with CohesionMoment law,$n,$N,$nb,$(kv steps "$r"),$(kv loop_wall "$r"),$(elapsed "$stem"),$(rss_mb "$stem"),$E_ANA,$(kv E_pulled "$fit"),$(kv ratio_pulled "$fit"),$(kv E_fixed "$fit"),$(kv ratio_fixed "$fit")" | tee -a "$CSV"
    else
      echo "Yade n=$n failed (see $stem.log)" >&2
    fi
  fi
  if has lammps; then
    stem=$OUT/logs/bonded_lammps_n$n
    if ( cd "$OUT/logs" && timed "$stem" lmp -in "$PEERS/lammps/in.bonded_tension" -var n "$n" -log "$stem.log" -screen none ); then
      fit=$(python3 "$PEERS/common/fit_modulus.py" "$OUT/logs/bonded_lammps_n$n.dat" $E_ANA)
      steps=$(grep 'Loop time' "$stem.log" | tail -1 | awk '{print $9}')
      echo "LAMMPS,$(version lammps),bond_style harmonic (kn = 2K; central springs only),$n,$N,$nb,$steps,$(loop_time "$stem.log"),$(elapsed "$stem"),$(rss_mb "$stem"),$E_ANA,$(kv E_pulled "$fit"),$(kv ratio_pulled "$fit"),$(kv E_fixed "$fit"),$(kv ratio_fixed "$fit")" | tee -a "$CSV"
    else
      echo "LAMMPS n=$n failed (see $stem.log)" >&2
    fi
  fi
done
