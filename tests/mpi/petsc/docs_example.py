#!/usr/bin/env python3
"""The worked example of docs/solvers.md: runs the page's block marked
`doc-test: run by petsc_docs_example` as written (build-mpi/bin is this build's bin folder) in a
fresh folder, then checks the page's claim: PETSc's CG + GAMG on two ranks gives the E and nu of
the in-house multigrid. Both solve to the relative residual 1e-10; E moves by at most
rho sqrt(kappa) <= 1e-10 * 1e4 = 1e-6 of itself (tests/mpi/petsc/petsc_agreement_test.cpp).

  docs_example.py SOURCE_DIR BIN_DIR
"""
import json
import os
import subprocess
import sys
import tempfile

MARK = "doc-test: run by petsc_docs_example"


def block(page):
    lines = open(page, encoding="utf-8").read().split("\n")
    for i, line in enumerate(lines):
        if MARK in line:
            start = i + 1
            while not lines[start].startswith("```"):
                start += 1
            end = start + 1
            while not lines[end].startswith("```"):
                end += 1
            return "\n".join(lines[start + 1:end]) + "\n"
    sys.exit(f"{page}: no block marked '{MARK}'")


def main():
    source, bindir = sys.argv[1], sys.argv[2]
    script = block(os.path.join(source, "docs", "solvers.md"))
    with tempfile.TemporaryDirectory() as tmp:
        os.makedirs(os.path.join(tmp, "build-mpi"))
        os.symlink(os.path.abspath(bindir), os.path.join(tmp, "build-mpi", "bin"))
        os.symlink(os.path.join(source, "docs"), os.path.join(tmp, "docs"))
        env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1")
        if os.geteuid() == 0:
            env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        r = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=tmp, env=env)
        if r.returncode != 0:
            sys.exit(f"docs/solvers.md worked example failed (exit {r.returncode})")
        amg = json.load(open(os.path.join(tmp, "amg.json")))["implicit"]
        petsc = json.load(open(os.path.join(tmp, "petsc.json")))["implicit"]
    print(f"E {amg['E']:.7e} (amg, {amg['iterations']} iterations) {petsc['E']:.7e} (petsc, {petsc['iterations']} iterations)")
    ok = petsc["solver"] == "petsc" and amg["solver"] == "amg"
    ok = ok and abs(petsc["E"] / amg["E"] - 1) <= 1e-6 and abs(petsc["nu"] - amg["nu"]) <= 1e-6
    ok = ok and petsc["residual"] <= 1e-9 and amg["residual"] <= 1e-9
    sys.exit(0 if ok else "PETSc and the in-house multigrid disagree beyond 1e-6 (or a solve did not converge)")


if __name__ == "__main__":
    main()
