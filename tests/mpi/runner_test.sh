#!/bin/sh
# tomodem-run of the MPI build starting a `ranks: 2` step through a real mpirun (issue 22 item 4):
# the launcher is TOMODEM_MPIRUN (the test sets "mpirun --oversubscribe"), the step is the MPI
# ping-pong, which writes its rank count into its CSV, so the step must have run as one MPI job
# of 2 ranks; a `tool:` step with ranks: 2 is accepted because the build's tools say
# "features: ... mpi"; the lock records the launch.
# usage: runner_test.sh TOMODEM_RUN PINGPONG
set -eu
run=$1 pingpong=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
"$run" --version | grep -qx 'features: openmp mpi petsc' || fail "tomodem-run --version has no 'features: openmp mpi petsc' line"
cat > "$dir/p.yaml" <<YAML
steps:
  pingpong:
    ranks: 2
    cmd: $pingpong --repeats 1 --csv \${outs.0}
    outs: [pp.csv]
YAML
# Only loaded (status runs nothing): `tomodem-run row` has no MPI code of its own, so 2 ranks would write row.json twice.
cat > "$dir/q.yaml" <<YAML
steps:
  row:
    tool: run
    ranks: 2
    args: [row, -o, '\${outs.0}', --value, 'a=1']
    outs: [row.json]
YAML
"$run" status "$dir/q.yaml" > /dev/null || fail "an MPI build refused a tool step with ranks: 2"
"$run" "$dir/p.yaml" -q 2> "$dir/err" || { cat "$dir/err" "$dir"/p.logs/* >&2; fail "the run failed"; }
grep -q '^allreduce,2,8,0,' "$dir/pp.csv" || fail "the ping-pong did not run as one job of 2 ranks: $(cat "$dir/pp.csv")"
grep -q '"launch": "mpirun --oversubscribe -np 2"' "$dir/p.lock.json" || fail "no launch in the lock: $(cat "$dir/p.lock.json")"
echo "OK: ranks: 2 ran through mpirun as one MPI job of 2 ranks"
