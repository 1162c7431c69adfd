#!/bin/bash
# PETSc (GAMG, hypre's BoomerAMG) against the in-house multigrid on the elastic systems of
# tomodem-young (docs/solvers.md, "How to choose"; issue 22 "How it is measured"): set-up and
# solve time, iterations, process CPU and peak RSS per rank, on 1 and 2 ranks.
#
# The networks are the tools' own (docs/solvers.md): random insertion at a solid fraction of 0.30
# (tomodem-pack, docs/examples/solvers/loose.yaml with --particles), homothetic densification and
# bonding to a relative density of 0.60 (tomodem-bond --rule density); 6 unknowns per particle,
# so 16 983 particles give ~1e5 unknowns and 169 742 ~1e6. All solves to a relative residual of
# 1e-10, --no-tensor (the three normal strain cases, E and nu).
#
# usage: tests/bench/mpi/petsc_bench.sh [SIZES...]      (default: 16983 169742)
# env:   BUILD_MPI=<repo>/build-mpi  OUT=<BUILD_MPI>/petsc-bench  MPIRUN=mpirun
#        CASES="amg gamg0 gamg02 gamg gamg2 boomeramg boomeramg2"  (which runs; 2: on two ranks;
#        gamg0, gamg02: tomodem's own GAMG settings without the tuning below, on one and two ranks:
#        the peak RSS per rank of the distributed assembly, docs/solvers.md; amgt2: the in-house
#        multigrid on two OpenMP threads)
#        PETSC_MEMORY=1: PETSc's own memory report for every PETSc case (-memory_view, -malloc_debug,
#        -log_view with -log_view_memory into <case>.log_view, -ksp_view into <case>.out; slower)
# out:   OUT/<particles>/<case>.json (the tool's summary, rank 0), <case>.time (/usr/bin/time -v of
#        every rank), results.csv: one line per run with the load average before and after.
set -u
REPO=$(cd "$(dirname "$0")/../../.." && pwd)
BUILD_MPI=${BUILD_MPI:-$REPO/build-mpi}
OUT=${OUT:-$BUILD_MPI/petsc-bench}
MPIRUN=${MPIRUN:-mpirun}
CASES=${CASES:-amg gamg0 gamg02 gamg gamg2 boomeramg boomeramg2}
SIZES=${*:-16983 169742}
BIN=$BUILD_MPI/bin
[ "$(id -u)" = 0 ] && export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE
die() { echo "petsc_bench: $*" >&2; exit 1; }
[ -x "$BIN/tomodem-young" ] || die "missing $BIN/tomodem-young: build the MPI build (-DTOMODEM_MPI=ON)"
command -v /usr/bin/time > /dev/null || die "needs /usr/bin/time (Debian package time)"
load() { cut -d' ' -f1 /proc/loadavg; }

# GAMG: tomodem always sets the particles' 6x6 blocks as smoother (point-block Jacobi under
# Chebyshev) and the rigid-body modes as near-null space (case gamg0). Cases gamg and gamg2 add
# what one tries next: smoothed aggregation with one smoothing step, a drop threshold of 0.01
# for the strength graph (bond stiffnesses span decades: weak bonds should not glue aggregates),
# the graph squared on the first level (fewer, larger aggregates). Measured: no gain at 1e5
# (docs/solvers.md), so tomodem does not set them.
GAMG="-pc_gamg_threshold 0.01 -pc_gamg_agg_nsmooths 1 -pc_gamg_square_graph 1"
# BoomerAMG for a 6-DOF elastic system: nodal (unknown-block) coarsening, interpolation that
# keeps the rigid-body modes (PETSc passes the near-null space), HMIS coarsening with extended+i
# interpolation and aggressive coarsening on the first level (hypre's advice for 3-D elasticity),
# strong threshold 0.5.
# (One line: PETSc reads a newline as part of the value.)
BOOMER="-pc_type hypre -pc_hypre_type boomeramg -pc_hypre_boomeramg_nodal_coarsen 6"
BOOMER+=" -pc_hypre_boomeramg_vec_interp_variant 2 -pc_hypre_boomeramg_coarsen_type HMIS"
BOOMER+=" -pc_hypre_boomeramg_interp_type ext+i -pc_hypre_boomeramg_strong_threshold 0.5"
BOOMER+=" -pc_hypre_boomeramg_agg_nl 1"

for n in $SIZES; do
  W=$OUT/$n
  mkdir -p "$W"
  cd "$W" || die "cannot enter $W"
  if [ ! -s bonded.h5 ]; then
    sed "s/^particles: .*/particles: $n/" "$REPO/docs/examples/solvers/loose.yaml" > loose.yaml
    "$BIN/tomodem-pack" loose.yaml -o loose.h5 --no-tessellation -q --json pack.json || die "pack failed"
    "$BIN/tomodem-bond" loose.h5 -o bonded.h5 --rule density --target-density 0.60 -q --json bond.json || die "bond failed"
  fi
  [ -s results.csv ] || echo "case,ranks,load_before,load_after,unknowns,iterations,levels,setup_s,solve_s,cpu_s_all_ranks,peak_rss_MB_per_rank,E" > results.csv
  for c in $CASES; do
    young=("$BIN/tomodem-young" bonded.h5 --no-tensor --tolerance 1e-10 -q --json "$c.json")
    case $c in
      amg)        env=""; cmd=(/usr/bin/time -v -o "$c.time" "${young[@]}" --solver amg --threads 1) ;;
      amgt2)      env=""; cmd=(/usr/bin/time -v -o "$c.time" "${young[@]}" --solver amg --threads 2) ;;
      gamg0)      env=""; cmd=(/usr/bin/time -v -o "$c.time" "${young[@]}" --solver petsc) ;;  # tomodem's GAMG settings only
      gamg02)     env=""; cmd=($MPIRUN --oversubscribe -np 2 sh -c '/usr/bin/time -v -o "$0.$OMPI_COMM_WORLD_RANK.time" "$@"' "$c" "${young[@]}" --solver petsc) ;;
      gamg)       env="$GAMG"; cmd=(/usr/bin/time -v -o "$c.time" "${young[@]}" --solver petsc) ;;
      boomeramg)  env="$BOOMER"; cmd=(/usr/bin/time -v -o "$c.time" "${young[@]}" --solver petsc) ;;
      gamg2)      env="$GAMG"; cmd=($MPIRUN --oversubscribe -np 2 sh -c '/usr/bin/time -v -o "$0.$OMPI_COMM_WORLD_RANK.time" "$@"' "$c" "${young[@]}" --solver petsc) ;;
      boomeramg2) env="$BOOMER"; cmd=($MPIRUN --oversubscribe -np 2 sh -c '/usr/bin/time -v -o "$0.$OMPI_COMM_WORLD_RANK.time" "$@"' "$c" "${young[@]}" --solver petsc) ;;
      *) die "unknown case $c" ;;
    esac
    [ "${PETSC_MEMORY:-0}" = 1 ] && env+=" -memory_view -malloc_debug -log_view :$c.log_view -log_view_memory -ksp_view"
    before=$(load)
    rm -f "$c".*time
    PETSC_OPTIONS="$env" "${cmd[@]}" > "$c.out" 2> "$c.err" || { echo "petsc_bench: $n $c failed: $(tail -3 "$c.err")" >&2; continue; }
    after=$(load)
    python3 - "$c" "$before" "$after" >> results.csv <<'EOF'
import glob, json, re, sys
c, before, after = sys.argv[1:4]
s = json.load(open(c + ".json"))
im = s["implicit"]
times = sorted(glob.glob(c + "*.time"))
cpu = rss = 0.0
for t in times:
    text = open(t).read()
    cpu += sum(float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)", text))
    rss = max(rss, float(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) / 1024)
get = lambda *k: next((im[x] for x in k if x in im), "")
print(",".join(str(v) for v in (c, len(times), before, after, get("dofs"), get("iterations"), get("multigrid_levels"),
                                get("setup_s"), get("solve_s"), round(cpu, 2), round(rss), s.get("E", im.get("E")))))
EOF
    tail -1 results.csv
  done
done
