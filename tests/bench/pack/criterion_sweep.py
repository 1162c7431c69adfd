#!/usr/bin/env python3
"""The error of a jammed packing against its run time (docs/pack.md, "The criterion against the run time").

Packs a config (default: the pressure-target bench input, Hertz alumina, lognormal sigma = 0.3 by
volume, 1 MPa) once per seed and per equilibrium criterion (tomodem-pack --seed and
--unbalanced-force-ratio, which override the config) and compares each
packing with the same seed's packing at the tightest criterion: what a looser criterion saves in
steps and CPU, what it changes in solid fraction, coordination and pressure, and how that change
compares with the scatter between seeds (the sample-to-sample error a user has anyway).

usage: criterion_sweep.py [--tool build/bin/tomodem-pack] [--config FILE] [--particles N]
                          [--seeds 12] [--criteria 1e-2,1e-3,1e-4] [--jobs 2] [--out DIR]
--particles overrides the config's count (the bench input has 10 000).
Each run uses one thread; --jobs runs go side by side. Prints a markdown table; DIR keeps every
run's JSON summary and log (a temporary folder when --out is not given); a run whose summary is
already in DIR is not run again, so a sweep can be resumed or extended by another criterion. A
summary written by another build (its provenance git hash is not the one --tool --version
prints), or a file there that is not a summary, is refused with exit 2 before anything is
written or run: results of two builds are not mixed in one table. A build from
a modified tree ("+dirty") cannot be told from another build of the same commit.
"""
import argparse
import concurrent.futures
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

CONFIG = """particles: {n}
initial_solid_fraction: 0.3
phases:
  - name: alumina
    material: {{youngs_modulus: 3.8e11, poisson_ratio: 0.22, density: 3950}}
    size_distribution: {{kind: lognormal, diameter: 1.0e-6, sigma: 0.3, basis: volume}}
contact: {{normal: hertz}}
target: {{pressure: 1.0e6}}
output: {{packing: packing.h5, tessellation: false}}
"""


def build_of(tool):
    """The git hash the tool was built from, as its --version prints it ("... (git 1a2b3c4d5e6f)")."""
    try:
        text = subprocess.run([tool, "--version"], capture_output=True, text=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError) as e:
        return None, str(e)
    m = re.search(r"\(git ([^)]+)\)", text)
    first = text.strip().splitlines()[0] if text.strip() else ""
    return (m.group(1), None) if m else (None, f"no git hash in its --version output {first!r}")


def run_file(out, seed, c, ext):
    """The file of one packing (criterion c, seed) in DIR: its summary (.json), log or packing."""
    return os.path.join(out, f"c{c}_s{seed}{ext}")


def run(tool, cfg, out, particles, seed, c):
    summary = run_file(out, seed, c, ".json")
    if os.path.exists(summary):  # a sweep resumed in the same DIR (its build checked in main)
        with open(summary) as f:
            return c, seed, json.load(f), 0
    with open(run_file(out, seed, c, ".log"), "w") as log:
        rc = subprocess.call([tool, cfg, "--seed", str(seed), "--unbalanced-force-ratio", c, "--threads", "1", "-q",
                              "-o", run_file(out, seed, c, ".h5"), "--json", summary]
                             + (["--particles", str(particles)] if particles else []),
                             stdout=log, stderr=subprocess.STDOUT)
    if rc != 0 or not os.path.exists(summary):
        return c, seed, None, rc
    with open(summary) as f:
        js = json.load(f)
    if js.get("unbalanced_force_criterion") != float(c):  # the override must have reached the run
        sys.exit(f"criterion_sweep.py: {summary} was packed at criterion {js.get('unbalanced_force_criterion')}, not {c}")
    return c, seed, js, rc


def median(xs):
    return statistics.median(xs) if xs else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tool", default="build/bin/tomodem-pack")
    ap.add_argument("--config", help="a tomodem-pack config (default: the bench input)")
    ap.add_argument("--particles", type=int, help="override the config's particle count")
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--criteria", default="1e-2,1e-3,1e-4")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out")
    a = ap.parse_args()
    def refuse(why):
        print("criterion_sweep.py: " + why, file=sys.stderr)
        sys.exit(2)
    try:
        criteria = [float(c) for c in a.criteria.split(",")]
    except ValueError:
        refuse(f"--criteria {a.criteria!r}: expected numbers separated by commas (1e-2,1e-3,1e-4)")
    if any(not c > 0 for c in criteria):
        refuse(f"--criteria {a.criteria!r}: every unbalanced-force ratio must be > 0")
    if a.seeds < 2 or len(set(criteria)) < 2:
        refuse("needs at least 2 seeds and 2 different criteria (a reference and one to compare)")
    if not (os.path.isfile(a.tool) and os.access(a.tool, os.X_OK)):
        refuse(f"--tool {a.tool}: not an executable file (build tomodem-pack first)")
    build, why = build_of(a.tool)
    if build is None:
        refuse(f"--tool {a.tool}: cannot tell which build it is ({why})")
    if a.config is not None and not os.path.isfile(a.config):
        refuse(f"--config {a.config}: no such file")
    out = a.out or tempfile.mkdtemp(prefix="tomodem-criterion.")
    os.makedirs(out, exist_ok=True)
    # Summaries already in DIR must come from this build: checked before anything is written or run.
    for s in range(1, a.seeds + 1):
        for c in criteria:
            summary = run_file(out, s, f"{c:g}", ".json")
            if not os.path.exists(summary):
                continue
            try:
                with open(summary) as f:
                    written_by = json.load(f).get("provenance", {}).get("git_hash")
            except (OSError, ValueError, AttributeError) as e:
                refuse(f"{summary}: not a tomodem-pack summary ({e}); use another --out or remove it")
            if written_by != build:
                refuse(f"{summary} was written by tomodem-pack of git {written_by}, --tool {a.tool} is git {build}: "
                       "use another --out (results of two builds are not mixed)")
    cfg = a.config
    if cfg is None:
        cfg = os.path.join(out, "bench_input.yaml")
        with open(cfg, "w") as f:
            f.write(CONFIG.format(n=10000))
    jobs = [(a.tool, cfg, out, a.particles, s, f"{c:g}") for s in range(1, a.seeds + 1) for c in criteria]
    res = {}
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        for c, seed, js, rc in pool.map(lambda j: run(*j), jobs):
            if js is None:
                print(f"criterion {c}, seed {seed}: tomodem-pack failed (exit {rc}), see {out}", file=sys.stderr)
            res[(float(c), seed)] = js
    ref = min(criteria)
    seeds = [s for s in range(1, a.seeds + 1) if res.get((ref, s))]
    refs = [res[(ref, s)] for s in seeds]
    if len(refs) < 2:
        sys.exit(f"criterion_sweep.py: fewer than two reference runs finished (see {out})")
    spread_phi = statistics.stdev(r["solid_fraction"] for r in refs)
    spread_z = statistics.stdev(r["coordination_no_rattlers"] for r in refs)
    print(f"{os.path.basename(cfg)}, N = {refs[0]['n_particles']}, seeds 1-{a.seeds}, one thread per run, {a.jobs} side by side; reference: "
          f"criterion {ref:g}; scatter between seeds at the reference (standard deviation): "
          f"solid fraction {spread_phi:.2e}, Z without rattlers {spread_z:.3f}; runs in {out}\n")
    print("| criterion | runs in equilibrium | median steps | median CPU s | median abs(dphi) | max abs(dphi) "
          "| median abs(dZ_nr) | max abs(dZ_nr) | max abs(p/P - 1) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for c in sorted(criteria, reverse=True):
        runs = [(s, res.get((c, s))) for s in seeds]
        ok = [(s, r) for s, r in runs if r]
        dphi = [abs(r["solid_fraction"] - res[(ref, s)]["solid_fraction"]) for s, r in ok]
        dz = [abs(r["coordination_no_rattlers"] - res[(ref, s)]["coordination_no_rattlers"]) for s, r in ok]
        dp = [abs(r["pressure"] / r["target_pressure"] - 1) for _, r in ok]
        eq = sum(1 for _, r in ok if r["equilibrium"] and r["target_reached"])
        print(f"| {c:g} | {eq} of {len(runs)} | {median([r['steps'] for _, r in ok]):.0f} "
              f"| {median([r['cpu_time_s'] for _, r in ok]):.1f} | {median(dphi):.1e} | {max(dphi):.1e} "
              f"| {median(dz):.3f} | {max(dz):.3f} | {max(dp):.1e} |")


if __name__ == "__main__":
    main()
