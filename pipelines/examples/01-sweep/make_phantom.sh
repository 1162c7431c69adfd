#!/bin/sh
# A deterministic stand-in for a segmented volume: N lines "index solid_fraction".
awk -v n="$1" 'BEGIN { srand(7); for (i = 0; i < n; i++) printf "%d %.4f\n", i, rand() }'
