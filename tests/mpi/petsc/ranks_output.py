#!/usr/bin/env python3
"""Rank 0 alone speaks and writes (docs/scaling.md, "Outputs on several ranks").

young, conduct and fracture run with PETSc under `mpirun -np 2` in an empty folder, and once
serially (no launcher) in another. Checked:
- stdout holds exactly one JSON summary and every progress line on stderr appears once;
- the folder holds exactly the files the command names (no second rank's temporary, no leftover);
- the numbers equal the serial run's to the solver tolerance: both solve to a relative residual
  of 1e-10, and a quantity linear in the solution then moves by at most rho sqrt(kappa) <=
  1e-10 * 1e4 = 1e-6 of itself (tests/mpi/petsc/petsc_agreement_test.cpp); the HDF5 fields by
  h5diff -p 1e-6 (relative), the JSON values to 1e-6;
- bad input (a missing packing, a refused option value) under mpirun: one error message,
  exit code 2 on both ranks, an empty folder.

  ranks_output.py BIN_DIR SOURCE_DIR MPIEXEC
"""
import json
import os
import re
import subprocess
import sys
import tempfile

BIN, SOURCE, MPIEXEC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), sys.argv[3]
ENV = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1")
if os.geteuid() == 0:
    ENV.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def run(args, cwd, ranks=0):
    """`args` in `cwd`, serially or under mpirun; each rank reports its own exit code on stderr
    (a shell around the tool), so mpirun does not stop at the first non-zero one."""
    tool = [os.path.join(BIN, args[0])] + args[1:]
    if ranks:
        cmd = [MPIEXEC, "--oversubscribe", "-np", str(ranks), "sh", "-c",
               '"$@"; echo "rank-exit $OMPI_COMM_WORLD_RANK $?" >&2', "sh"] + tool
    else:
        cmd = tool
    return subprocess.run(cmd, cwd=cwd, env=ENV, capture_output=True, text=True)


def rank_exits(r):
    return sorted(int(c) for c in re.findall(r"^rank-exit \d+ (\d+)$", r.stderr, re.M))


def messages(r):
    return [l for l in r.stderr.splitlines() if l.startswith("tomodem-")]


def close(a, b, rel):
    """Every number of two JSON values within `rel` (relative to the larger); strings equal."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(close(a[k], b[k], rel) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(close(x, y, rel) for x, y in zip(a, b))
    if isinstance(a, bool) or a is None or isinstance(a, str):
        return a == b
    return abs(a - b) <= rel * max(abs(a), abs(b), 1e-300)


def results(summary, keys):
    return {k: summary[k] for k in keys}


def largest(path, dataset):
    """The largest |value| of a dataset (h5dump's text)."""
    text = subprocess.run(["h5dump", "-d", dataset, path], capture_output=True, text=True).stdout
    data = text.split("DATA {", 1)[-1]
    return max((abs(float(x)) for x in re.findall(r"[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?", re.sub(r"\(\d+\):", "", data))),
               default=0.0)


def same_h5(a, b):
    """Every dataset equal to 1e-6 of its largest value. A value that is a difference of large
    ones (a dead-end edge's current, ~1e-10 of the largest) moves by rho times the largest, so
    its own relative change means nothing: h5diff -p finds the datasets that differ at all, and
    those are compared again with the absolute delta 1e-6 * max|value| (h5diff -d). h5diff also
    compares attributes; the creation time and the command line differ between the runs."""
    r = subprocess.run(["h5diff", "-r", "-p", "1e-6", a, b], capture_output=True, text=True)
    differing, current, datasets = [], "", 0
    for line in r.stdout.splitlines():  # "dataset: </a> and </a>" then "N differences found"
        if line.startswith(("dataset:", "attribute:")):
            current = line
            datasets += line.startswith("dataset:")
        m = re.match(r"(\d+) differences? found", line)
        if m and current.startswith("dataset:") and int(m.group(1)) > 0:
            differing.append(re.match(r"dataset: <([^>]*)>", current).group(1))
    bad = []
    for ds in differing:
        delta = 1e-6 * largest(a, ds)
        d = subprocess.run(["h5diff", "-d", repr(delta), a, b, ds], capture_output=True, text=True)
        if d.returncode != 0:
            bad.append(f"{ds} (delta {delta:.3g}): {d.stdout.strip()[-200:]}")
    return datasets > 0 and not bad, "\n".join(bad[:5]) or f"{datasets} datasets compared"


def case(name, args, outputs, keys, h5=None):
    with tempfile.TemporaryDirectory() as serial, tempfile.TemporaryDirectory() as par:
        for d in (serial, par):
            os.symlink(os.path.join(NET, "bonded.h5"), os.path.join(d, "bonded.h5"))
        s = run(args + ["--json", "serial.json"], serial)
        check(s.returncode == 0, f"{name}: serial run (exit {s.returncode}) {s.stderr[-300:]}")
        p = run(args, par, ranks=2)
        check(rank_exits(p) == [0, 0], f"{name}: both ranks exit 0 ({rank_exits(p)}) {p.stderr[-300:]}")
        try:
            summary = json.loads(p.stdout)  # exactly one JSON document, or this fails
            one = True
        except json.JSONDecodeError:
            summary, one = None, False
        check(one and p.stdout.count('"provenance"') == 1, f"{name}: one summary on stdout")
        lines = messages(p)
        check(len(lines) == len(set(lines)), f"{name}: every message once ({len(lines)} lines)")
        left = sorted(set(os.listdir(par)) - {"bonded.h5"})
        check(left == sorted(outputs), f"{name}: the folder holds {left}, expected {sorted(outputs)}")
        if summary is not None and s.returncode == 0:
            ref = json.load(open(os.path.join(serial, "serial.json")))
            a, b = results(summary, keys), results(ref, keys)
            check(close(a, b, 1e-6), f"{name}: {keys} equal the serial run's to 1e-6")
        if h5 and s.returncode == 0 and h5 in left:
            ok, diff = same_h5(os.path.join(serial, h5), os.path.join(par, h5))
            check(ok, f"{name}: {h5} equals the serial run's to 1e-6 {diff}")


def bad(name, args):
    with tempfile.TemporaryDirectory() as par:
        p = run(args, par, ranks=2)
        errors = [l for l in messages(p) if "error:" in l]
        check(len(errors) == 1, f"{name}: one error message ({errors})")
        check(rank_exits(p) == [2, 2], f"{name}: exit 2 on both ranks ({rank_exits(p)})")
        check(os.listdir(par) == [], f"{name}: nothing left behind ({os.listdir(par)})")


with tempfile.TemporaryDirectory() as NET:
    # A 400-particle bonded packing (docs/solvers.md's recipe, smaller).
    yaml = open(os.path.join(SOURCE, "docs", "examples", "solvers", "loose.yaml")).read()
    # Conducting and with a surface energy, so conduct and fracture (lefm) run on it too.
    yaml = yaml.replace("particles: 3000", "particles: 400").replace(
        "density: 2500}", "density: 2500, conductivity: 1.0e5, surface_energy: 1.0}")
    open(os.path.join(NET, "loose.yaml"), "w").write(yaml)
    for args in (["tomodem-pack", "loose.yaml", "-o", "loose.h5", "--no-tessellation", "-q", "--json", "pack.json"],
                 ["tomodem-bond", "loose.h5", "-o", "bonded.h5", "--rule", "density", "--target-density", "0.60",
                  "-q", "--json", "bond.json"]):
        r = run(args, NET)
        if r.returncode != 0:
            sys.exit(f"{args[0]} failed: {r.stderr}")

    case("young", ["tomodem-young", "bonded.h5", "--solver", "petsc", "--tolerance", "1e-10"],
         [], ["E", "nu"])
    case("conduct", ["tomodem-conduct", "bonded.h5", "--preconditioner", "petsc", "--tolerance", "1e-10",
                     "--axis", "x", "-o", "fields.h5"],
         ["fields.h5", "fields.xdmf"], ["sigma_eff"], h5="fields.h5")
    case("fracture", ["tomodem-fracture", "bonded.h5", "--method", "sla", "--sla-solver", "petsc",
                      "--cg-tolerance", "1e-10", "--a-over-w", "0.25", "--stop-fraction", "0.5",
                      "--curve", "curve.csv", "--map", "cracks.h5"],
         ["curve.csv", "cracks.h5", "cracks.xdmf"], ["K_IC", "E"], h5="cracks.h5")
    bad("young, missing input", ["tomodem-young", "missing.h5", "--solver", "petsc", "--json", "out.json"])
    bad("conduct, refused tolerance", ["tomodem-conduct", os.path.join(NET, "bonded.h5"), "--preconditioner",
                                       "petsc", "--tolerance", "-1", "-o", "fields.h5", "--json", "out.json"])

sys.exit(1 if failures else 0)
