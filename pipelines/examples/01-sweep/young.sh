#!/bin/sh
# Stand-in for tomodem-young: E/E_s = density^2 (Gibson-Ashby) with a +-2 % seeded scatter.
awk -v s="$2" '/^density/ { d = $2 } END { srand(s); printf "%s,%d,%.5f\n", d, s, d * d * (1 + 0.04 * (rand() - 0.5)) }' "$1"
