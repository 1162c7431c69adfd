#!/bin/sh
# Stand-in for tomodem-pack: VOLUME DENSITY PARTICLES -> a small key-value "packing".
echo "density $2"
echo "particles $3"
echo "voxels $(wc -l < "$1")"
