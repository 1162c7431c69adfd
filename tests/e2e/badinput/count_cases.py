#!/usr/bin/env python3
"""Counts the bad-input cases per tool in every table (docs/reliability.md quotes its output).

    python3 tests/e2e/badinput/count_cases.py [BUILD_BIN_DIR]

Sources: the cross-tool table (tests/e2e/badinput/badinput_test.cpp, one line per row), the
per-tool tables that run in a loop (tests/e2e/{dem,pack,sinter}: one `row(...)` call or one
`{"name", {{...}}` literal per case), the parameterised per-tool tables (listed by their test
binaries with --gtest_list_tests; valid-input controls such as TheValidInputsRun and *Ok rows are
not counted) and the tomodem-run safety tests (tests/e2e/pipeline/safety_test.cpp, one TEST each).
Rows marked open (skipped) in the cross-tool table are counted apart.
"""
import collections
import os
import re
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
BIN = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "bin")
TOOLS = ["segment", "phantom", "pack", "carve", "bond", "young", "fracture", "conduct", "dem", "sinter", "run"]


def read(rel):
    with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
        return f.read()


def cross_tool():
    rows, open_rows = collections.Counter(), collections.Counter()
    text = read("tests/e2e/badinput/badinput_test.cpp")
    table = text[text.index("const std::vector<Row> kRows"):text.index("// Valid inputs, made once")]
    for m in re.finditer(r'^\s+\{"(\w+)", "(?:[^"\\]|\\.)*", \d+, \{[^\n]*?\}(,\s*\n\s*"|\},)', table, re.M):
        rows[m.group(1)] += 1
        if m.group(2) != "},":
            open_rows[m.group(1)] += 1
    return rows, open_rows


def loop_table(rel):
    text = read(rel)
    calls = len(re.findall(r'^\s+\w*row\("', text, re.M))
    literals = len(re.findall(r'^\s+\{"[A-Za-z0-9_]+", \{\{', text, re.M))
    return calls + literals


def listed(binary):
    path = os.path.join(BIN, binary)
    if not os.access(path, os.X_OK):
        return None
    out = subprocess.run([path, "--gtest_list_tests"], capture_output=True, text=True).stdout
    names = [l.split()[0].split("/")[-1] for l in out.splitlines() if l.startswith("  ")]
    return [n for n in names if not n.startswith("TheValidInput") and not n.endswith("Ok")]


def main():
    per = collections.defaultdict(collections.Counter)  # tool -> source -> cases
    rows, open_rows = cross_tool()
    for t, n in rows.items():
        per[t]["cross-tool"] += n
    for tool, rel in [("dem", "tests/e2e/dem/test_dem_bad_input.cpp"), ("pack", "tests/e2e/pack/test_pack_bad_input.cpp"),
                      ("sinter", "tests/e2e/sinter/test_sinter_bad_input.cpp")]:
        if os.path.exists(os.path.join(ROOT, rel)):
            per[tool]["per-tool"] += loop_table(rel)
    for binary, tool in [("carve_bad_input_e2e", "carve"), ("conduct_bad_input_e2e", "conduct"),
                         ("fracture_bad_input_e2e", "fracture"), ("young_bad_input_e2e", None),
                         ("test_image_badinput_e2e", None)]:
        names = listed(binary)
        if names is None:
            print(f"note: {binary} not built; its rows are not counted", file=sys.stderr)
            continue
        for n in names:
            t = tool
            if t is None:
                t = ("bond" if n.startswith("bond_") else "young" if n.startswith("young_") else
                     "segment" if n.startswith("Seg") else "phantom" if n.startswith("Phantom") else None)
            if t:
                per[t]["per-tool"] += 1
    safety = "tests/e2e/pipeline/safety_test.cpp"
    if os.path.exists(os.path.join(ROOT, safety)):
        per["run"]["per-tool"] += len(re.findall(r"^TEST\(", read(safety), re.M))
    print("| tool | cross-tool table | of which open | per-tool tables | total |")
    print("|---|---:|---:|---:|---:|")
    total = collections.Counter()
    for t in TOOLS:
        c = per[t]
        s = c["cross-tool"] + c["per-tool"]
        total.update({"cross": c["cross-tool"], "open": open_rows[t], "per": c["per-tool"], "all": s})
        print(f"| tomodem-{t} | {c['cross-tool']} | {open_rows[t]} | {c['per-tool']} | {s} |")
    print(f"| **all** | {total['cross']} | {total['open']} | {total['per']} | {total['all']} |")


if __name__ == "__main__":
    main()
