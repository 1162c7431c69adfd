#!/bin/sh
# The worked example of docs/dem.md, "Running on several ranks": scene A (12³ spheres, 300 steps)
# undecomposed and on 3 ranks print the same pressure, coordination and position checksum, and
# the checksum is the one the page shows.
# usage: doc_example.sh MPIEXEC BENCH DOCS_DEM_MD
set -e
mpiexec=$1 bench=$2 doc=$3
keys='pressure_Pa|coordination|position_checksum_m'
serial=$("$mpiexec" --oversubscribe -np 1 "$bench" --serial --lattice 12 --steps 300 --warm 0 | grep -E "^($keys) ")
ranks3=$("$mpiexec" --oversubscribe -np 3 "$bench" --lattice 12 --steps 300 --warm 0 | grep -E "^($keys) ")
echo "serial:"; echo "$serial"; echo "3 ranks:"; echo "$ranks3"
[ -n "$serial" ] || { echo "FAIL: the bench printed none of $keys"; exit 1; }
[ "$serial" = "$ranks3" ] || { echo "FAIL: 3 ranks differ from the serial run"; exit 1; }
sum=$(echo "$serial" | grep position_checksum_m)
grep -qF "$sum" "$doc" || { echo "FAIL: $doc does not show '$sum'"; exit 1; }
echo "OK"
