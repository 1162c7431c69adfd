#!/usr/bin/env python3
"""Docs are tests: run the marked shell blocks of README.md and docs/*.md (issue 21).

Every fenced block whose language is a shell (sh, bash, shell, console) or is left empty carries
a marker on the line(s) right above its fence, HTML comments that Markdown does not show:

  <!-- doc-test: run -->                       run the block as written
  <!-- doc-test: run small: 'A' -> 'B'; ... -->  run it with these replacements (each must occur):
                                               the documented smaller variant of a long example
  <!-- doc-test: run by TEST: note -->         run by the ctest test TEST (not run twice here)
  <!-- doc-test: skip: why -->                 not run, and why
  <!-- doc-test: before: COMMAND -->           a set-up command run before the block (not shown)
  <!-- doc-test: expect FILE:JSON.PATH = V ± T -->  a number the page states, compared after the
  <!-- doc-test: expect output /REGEX/ = V ± T -->  block (T absolute, or relative as "5%")

Any other block may carry  <!-- doc-test: file NAME -->  (its text is written to NAME in the
page's folder before the blocks after it run) or  <!-- doc-test: shipped PATH -->  (its text must
equal the shipped file PATH of the repository, so a page cannot drift from its example).

Each page runs in order in a fresh temporary folder holding `build/bin` (the build's tools, also
on PATH), `data` (the shipped data) and copies of `docs/examples` and `pipelines`, as a reader
who follows the page from a checkout would. A failure names the page and line and exits 1.

  run_docs.py --source DIR --bin DIR PAGE.md ...   run pages
  run_docs.py --source DIR --check                 every block marked; counts; exit 1 otherwise
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

SHELL_LANGS = {"", "sh", "bash", "shell", "console"}
MARK = re.compile(r"^\s*<!--\s*doc-test:\s*(.*?)\s*-->\s*$")
FENCE = re.compile(r"^(\s*)(```+|~~~+)\s*([A-Za-z0-9_+-]*)")
EXPECT = re.compile(r"^expect\s+(\S+?)(?::(\S+)|\s+/(.*)/)\s*=\s*(\S+)\s*(?:±|\+-)\s*(\S+?)(%?)$")
SMALL_SUB = re.compile(r"'((?:[^'\\]|\\.)*)'\s*->\s*'((?:[^'\\]|\\.)*)'")


class DocError(Exception):
    pass


class Block:
    def __init__(self, page, line, lang, text, marks):
        self.page, self.line, self.lang, self.text, self.marks = page, line, lang, text, marks

    @property
    def shell(self):
        return self.lang in SHELL_LANGS

    def where(self):
        return f"{self.page}:{self.line}"


def blocks_of(path, name):
    """Fenced blocks of a page with the doc-test markers right above each fence."""
    lines = open(path, encoding="utf-8").read().split("\n")
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, lang, start = m.group(2), m.group(3).lower(), i
        j = i + 1
        while j < len(lines) and not lines[j].strip().startswith(fence[:3]):
            j += 1
        marks, k = [], start - 1
        while k >= 0 and MARK.match(lines[k]):
            marks.insert(0, (k + 1, MARK.match(lines[k]).group(1)))
            k -= 1
        indent = len(m.group(1))
        text = "\n".join(l[indent:] if l[:indent].strip() == "" else l for l in lines[start + 1:j]) + "\n"
        out.append(Block(name, start + 1, lang, text, marks))
        i = j + 1
    return out


def parse_marks(b):
    """The block's directives: kind (run/run-by/skip/file/shipped/None), details, expects."""
    kind, detail, before, expects = None, None, [], []
    for line, m in b.marks:
        where = f"{b.page}:{line}"
        if m == "run" or m.startswith("run small:"):
            subs = []
            if m.startswith("run small:"):
                spec = m[len("run small:"):]
                subs = [(a.replace("\\'", "'"), c.replace("\\'", "'")) for a, c in SMALL_SUB.findall(spec)]
                if not subs:
                    raise DocError(f"{where}: 'run small:' needs 'OLD' -> 'NEW' replacements: {m!r}")
            kind, detail = "run", subs
        elif m.startswith("run by "):
            name = m[len("run by "):].split(":")[0].strip()
            if not name:
                raise DocError(f"{where}: 'run by' names no test: {m!r}")
            kind, detail = "run-by", name
        elif m.startswith("skip:"):
            if not m[len("skip:"):].strip():
                raise DocError(f"{where}: 'skip:' needs a reason")
            kind, detail = "skip", m[len("skip:"):].strip()
        elif m.startswith("file "):
            kind, detail = "file", m[len("file "):].strip()
        elif m.startswith("shipped "):
            kind, detail = "shipped", m[len("shipped "):].strip()
        elif m.startswith("before:"):
            before.append(m[len("before:"):].strip())
        elif m.startswith("expect"):
            e = EXPECT.match(m)
            if not e:
                raise DocError(f"{where}: cannot read {m!r} (expect FILE:PATH = V ± T, or expect output /RE/ = V ± T)")
            src, path, regex, value, tol, pct = e.groups()
            expects.append(dict(where=where, src=src, path=path, regex=regex, value=float(value),
                                tol=float(tol), relative=pct == "%", text=m))
        else:
            raise DocError(f"{where}: unknown doc-test marker {m!r}")
    if (expects or before) and kind != "run":
        raise DocError(f"{b.where()}: 'expect' and 'before' belong to a block marked run")
    return kind, detail, before, expects


def pages(source):
    docs = os.path.join(source, "docs")
    names = ["README.md"] + sorted("docs/" + f for f in os.listdir(docs) if f.endswith(".md"))
    return [(os.path.join(source, n), n) for n in names]


def json_at(data, path, where):
    cur = data
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", path):
        try:
            cur = cur[int(part[1:-1])] if part.startswith("[") else cur[part]
        except (KeyError, IndexError, TypeError):
            raise DocError(f"{where}: no '{path}' in the JSON (stops at '{part}')")
    return cur


def compare(e, folder, output):
    if e["src"] == "output":
        m = re.search(e["regex"], output, re.M)
        if not m:
            raise DocError(f"{e['where']}: /{e['regex']}/ not found in the block's output:\n{output[-2000:]}")
        got = float(m.group(1) if m.groups() else m.group(0))
    else:
        f = os.path.join(folder, e["src"])
        if not os.path.exists(f):
            raise DocError(f"{e['where']}: the block did not write {e['src']}")
        got = json_at(json.load(open(f)), e["path"], e["where"])
        if isinstance(got, bool):  # true/false compare as 1/0
            got = float(got)
        if not isinstance(got, (int, float)):
            raise DocError(f"{e['where']}: {e['src']}:{e['path']} is {got!r}, not a number")
    tol = e["tol"] * abs(e["value"]) / 100 if e["relative"] else e["tol"]
    if not abs(got - e["value"]) <= tol:
        raise DocError(f"{e['where']}: {e['text']}: the run gives {got}")
    return got


def prepare(folder, source, bindir):
    os.makedirs(os.path.join(folder, "build"))
    os.symlink(os.path.abspath(bindir), os.path.join(folder, "build", "bin"))
    os.symlink(os.path.join(source, "data"), os.path.join(folder, "data"))
    for sub in ("docs/examples", "pipelines"):
        src = os.path.join(source, sub)
        if os.path.isdir(src):
            shutil.copytree(src, os.path.join(folder, sub), symlinks=True)


def run_page(path, name, source, bindir, timeout, keep):
    counts = dict(run=0, run_by=0, skip=0, numbers=0, files=0)
    blocks = blocks_of(path, name)
    folder = tempfile.mkdtemp(prefix="doc-test-")
    env = dict(os.environ, PATH=os.path.abspath(bindir) + os.pathsep + os.environ.get("PATH", ""),
               OMP_WAIT_POLICY=os.environ.get("OMP_WAIT_POLICY", "PASSIVE"))
    try:
        prepare(folder, source, bindir)
        for b in blocks:
            kind, detail, before, expects = parse_marks(b)
            if kind is None:  # an unmarked shell block fails docs_marked (--check), not the page
                if b.shell:
                    print(f"{b.where()}: shell block without a doc-test marker (not run)")
                continue
            if kind == "shipped":
                shipped = os.path.join(source, detail)
                if not os.path.isfile(shipped):
                    raise DocError(f"{b.where()}: the page shows {detail}, which does not ship")
                if open(shipped, encoding="utf-8").read() != b.text:
                    raise DocError(f"{b.where()}: the block differs from the shipped {detail}")
                counts["files"] += 1
                continue
            if kind == "file":
                dest = os.path.join(folder, detail)
                os.makedirs(os.path.dirname(dest) or folder, exist_ok=True)
                open(dest, "w", encoding="utf-8").write(b.text)
                counts["files"] += 1
                continue
            if kind in ("skip", "run-by"):
                counts["skip" if kind == "skip" else "run_by"] += 1
                continue
            text = b.text
            for old, new in detail:
                if old not in text:
                    raise DocError(f"{b.where()}: the small variant's '{old}' is not in the block")
                text = text.replace(old, new)
            if b.lang == "python":  # a Python snippet runs as a script after the set-up commands
                # ParaView's modules load only in its own interpreter (Debian's python3-paraview).
                # Debian's python3-* packages (h5py) are for /usr/bin/python3, which a pyenv or venv
                # python3 earlier on PATH lacks.
                python = ("pvpython --force-offscreen-rendering" if "paraview" in text
                          else "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else "python3")
                before.append(python + " - <<'DOC_TEST_PYTHON'\n" + text + "DOC_TEST_PYTHON")
                text = ""
            elif not b.shell:
                raise DocError(f"{b.where()}: a ```{b.lang} block cannot run (sh or python)")
            script = "set -e -o pipefail\n" + "".join(c + "\n" for c in before) + text
            print(f"--- {b.where()}\n{(text or before[-1]).rstrip()}", flush=True)
            try:
                p = subprocess.run(["bash", "-c", script], cwd=folder, env=env, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True, timeout=timeout)
            except subprocess.TimeoutExpired:
                raise DocError(f"{b.where()}: the block ran past {timeout} s")
            if p.returncode != 0:
                raise DocError(f"{b.where()}: the block failed (exit {p.returncode}):\n{p.stdout[-4000:]}")
            counts["run"] += 1
            for e in expects:
                got = compare(e, folder, p.stdout)
                counts["numbers"] += 1
                print(f"    {e['text']}: {got}")
    finally:
        if keep:
            print(f"(kept {folder})")
        else:
            shutil.rmtree(folder, ignore_errors=True)
    return counts


def known_tests(source):
    """Names a `run by` may cite: ctest/GoogleTest names and executables found in tests/."""
    text = []
    for root, _, files in os.walk(os.path.join(source, "tests")):
        for f in files:
            if f.endswith((".txt", ".cpp", ".hpp", ".py", ".sh", ".cmake")):
                try:
                    text.append(open(os.path.join(root, f), encoding="utf-8", errors="replace").read())
                except OSError:
                    pass
    return "\n".join(text)


def check(source):
    """Every shell block marked, every marker readable; the counts."""
    tests, unmarked, errors = known_tests(source), [], []
    counts = dict(pages=0, blocks=0, run=0, run_small=0, run_by=0, skip=0, numbers=0, files=0)
    for path, name in pages(source):
        counts["pages"] += 1
        for b in blocks_of(path, name):
            try:
                kind, detail, _, expects = parse_marks(b)
            except DocError as e:
                errors.append(str(e))
                continue
            if kind == "run-by":
                test = detail.split(".")[-1]
                if test not in tests:
                    errors.append(f"{b.where()}: 'run by {detail}': no such test under tests/")
            if kind in ("file", "shipped"):
                counts["files"] += 1
                continue
            if not b.shell and kind is None:
                continue
            counts["blocks"] += 1
            if kind is None:
                unmarked.append(b.where())
            elif kind == "run":
                counts["run"] += 1
                counts["run_small"] += bool(detail)
                counts["numbers"] += len(expects)
            elif kind == "run-by":
                counts["run_by"] += 1
            elif kind == "skip":
                counts["skip"] += 1
    print("doc-test: {pages} pages, {blocks} shell blocks: {run} run here ({run_small} as their small variant), "
          "{run_by} run by other tests, {skip} skipped; {numbers} numbers compared; {files} example files".format(**counts))
    for u in unmarked:
        print(f"{u}: shell block without a doc-test marker")
    for e in errors:
        print(e)
    return 0 if not unmarked and not errors else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--source", required=True, help="the repository root")
    ap.add_argument("--bin", help="the build's bin/ folder")
    ap.add_argument("--check", action="store_true", help="only check that every shell block is marked")
    ap.add_argument("--timeout", type=float, default=600, help="seconds per block (default 600)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder")
    ap.add_argument("pages", nargs="*", help="pages, relative to --source (README.md, docs/pack.md)")
    a = ap.parse_args()
    source = os.path.abspath(a.source)
    if a.check:
        return check(source)
    if not a.bin or not os.path.isdir(a.bin):
        print(f"run_docs.py: field '--bin': value '{a.bin}': not a folder", file=sys.stderr)
        return 2
    total = dict(run=0, run_by=0, skip=0, numbers=0, files=0)
    for page in a.pages:
        path = os.path.join(source, page)
        if not os.path.isfile(path):
            print(f"run_docs.py: field 'page': value '{page}': no such page", file=sys.stderr)
            return 2
        try:
            c = run_page(path, page, source, a.bin, a.timeout, a.keep)
        except DocError as e:
            print(f"FAILED {e}", file=sys.stderr)
            return 1
        for k in total:
            total[k] += c[k]
        print(f"{page}: {c['run']} blocks run, {c['numbers']} numbers compared, {c['run_by']} run by other tests, "
              f"{c['skip']} skipped, {c['files']} files written or checked")
    return 0


if __name__ == "__main__":
    sys.exit(main())
