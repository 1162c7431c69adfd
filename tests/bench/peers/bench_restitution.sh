#!/bin/bash
# Effective normal restitution of each code's scene-A contact model (requested e = 0.5), two
# spheres head-on at 0.1 and 1 m/s each. See README.md.
#
# usage: bench_restitution.sh           env: CODES="lammps liggghts yade"  OUT  PIN
# out:   OUT/results/restitution.txt (one "RESTITUTION code=... V=... e=..." line per run)
set -u
source "$(dirname "$0")/common/lib.sh"
CODES=${CODES:-lammps liggghts yade}
has() { [[ " $CODES " == *" $1 "* ]]; }
has lammps && need lmp
has liggghts && need liggghts
has yade && need yade
TXT=$OUT/results/restitution.txt
: > "$TXT"
cd "$OUT/logs" || exit 1
for V in 0.1 1.0; do
  if has lammps; then
    for style in granular hertzhist; do
      $PIN lmp -in "$PEERS/lammps/in.restitution" -var V $V -var STYLE $style -log none 2>&1 | grep '^RESTITUTION' | tee -a "$TXT"
    done
  fi
  has liggghts && $PIN liggghts -in "$PEERS/liggghts/in.restitution" -var V $V -log none 2>&1 | grep '^RESTITUTION' | tee -a "$TXT"
  has yade && $PIN yade -n -x -j1 "$PEERS/yade/restitution.py" $V 2>&1 | grep '^RESTITUTION' | tee -a "$TXT"
done
[ -s "$TXT" ] || die "no code printed a restitution"
