#!/bin/bash
# LAMMPS's own granular example, run unmodified as a reference speed: examples/pour/in.pour of the
# Debian package lammps-examples (3000 spheres poured into a box with gran/hooke/history, then a
# chute flow at 26 degrees; LJ units). The `bench/in.chute` benchmark is not shipped by Debian.
#
# usage: bench_pour.sh                  env: OUT  PIN  POUR=<path of in.pour>
# out:   OUT/results/pour.txt (loop times, neighbour builds, peak memory)
set -u
source "$(dirname "$0")/common/lib.sh"
need lmp /usr/bin/time
POUR=${POUR:-/usr/share/lammps/examples/pour/in.pour}
[ -f "$POUR" ] || die "$POUR not found: install the Debian package lammps-examples, or set POUR"
mkdir -p "$OUT/pour" && cp "$POUR" "$OUT/pour/in.pour" || exit 1
stem=$OUT/logs/lammps_pour
( cd "$OUT/pour" && timed "$stem" lmp -in in.pour -log "$stem.log" -screen none ) || die "the pour example failed (see $stem.log)"
{ grep -E 'Loop time|Neighbor list builds' "$stem.log"; awk -F: '/Maximum resident|Elapsed/' "$stem.time"; } | tee "$OUT/results/pour.txt"
