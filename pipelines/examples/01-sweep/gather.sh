#!/bin/sh
# Stand-in for the gather step: one CSV with a header.
echo "density,seed,E_rel"
cat "$@"
