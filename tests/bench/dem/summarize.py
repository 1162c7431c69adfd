#!/usr/bin/python3
"""Summarise tests/bench/run_bench.sh: medians of the repeats, ratio to the faster peer, the
2-thread speed-up, memory per particle. Prints the markdown and replaces the block between
<!-- BEGIN GENERATED --> and <!-- END GENERATED --> of the given doc (created if missing), so
the hand-written parts of docs/benchmarks.md survive a re-run.
usage: summarize.py runs.csv docs/benchmarks.md --meta key=value ..."""
import csv, statistics, sys, os

BEGIN, END = "<!-- BEGIN GENERATED -->", "<!-- END GENERATED -->"
PEERS = ["lammps-granular", "lammps-hertzhist", "liggghts"]
ORDER = PEERS + ["tomodem-1t", "tomodem-2t", "tomodem-linear-frictionless-1t"]
LABEL = {
    "lammps-granular": "LAMMPS `pair granular` hertz/material+mindlin+tsuji",
    "lammps-hertzhist": "LAMMPS `gran/hertz/history`",
    "liggghts": "LIGGGHTS `gran model hertz tangential history`",
    "tomodem-1t": "**tomodem** Hertz+Mindlin, 1 thread",
    "tomodem-2t": "**tomodem** Hertz+Mindlin, 2 threads",
    "tomodem-linear-frictionless-1t": "tomodem linear frictionless, 1 thread",
}


def main():
    runs, doc = sys.argv[1], sys.argv[2]
    meta = {}
    if "--meta" in sys.argv:
        for kv in sys.argv[sys.argv.index("--meta") + 1:]:
            k, _, v = kv.partition("=")
            meta[k] = v
    rows = list(csv.DictReader(open(runs)))
    cells = {}
    for r in rows:
        cells.setdefault((r["variant"], int(r["N"]), r["config"]), []).append(r)

    def med(variant, N, config, key):
        rs = cells.get((variant, N, config), [])
        vals = [float(r[key]) for r in rs if r[key] not in ("", None)]
        return statistics.median(vals) if vals else None

    out = []
    out.append(f"Run {meta.get('date','?')} on {meta.get('cpu','?')} ({meta.get('cores','?')} vCPUs), "
               f"kernel {meta.get('kernel','?')}, Debian {meta.get('debian','?')}; LAMMPS `{meta.get('lammps','?')}`, "
               f"LIGGGHTS `{meta.get('liggghts','?')}`; tomodem commit {meta.get('commit','?')} built with "
               f"{meta.get('compiler','?')} (Release, {meta.get('native','?')}). Load average (1/5/15 min) before the run "
               f"{meta.get('load_before','?')}, after {meta.get('load_after','?')}. {meta.get('warm','?')} warm-up "
               f"steps, then {meta.get('steps','?')} timed steps; **medians of {meta.get('repeats','?')} repeats** "
               f"run one after the other with the codes interleaved; pinning: {meta.get('pin','none')}. "
               f"Raw runs: `tests/bench/dem/last_run.csv`.\n")
    variants = sorted({k[0] for k in cells}, key=lambda v: 0 if v == "scene" else 1)
    for variant in variants:
        Ns = sorted({k[1] for k in cells if k[0] == variant})
        title = ("Scene A, dense periodic Hertz–Mindlin" if variant == "scene"
                 else "Scene A-gas (FCC, 1 m/s, neighbour lists rebuilt)")
        out.append(f"### {title}\n")
        out.append("| code | N | particle-steps/s | ratio to faster peer | 2-thread speed-up | peak RSS MB | RSS/N kB | p Pa | Z | KE J | rebuilds (timed) |")
        out.append("|---|---|---|---|---|---|---|---|---|---|---|")
        for N in Ns:
            peer = [(med(variant, N, c, "pps") or 0, c) for c in PEERS]
            best, best_c = max(peer)
            for c in ORDER:
                pps = med(variant, N, c, "pps")
                if pps is None:
                    continue
                ratio = f"{pps / best:.2f}" if best > 0 else "–"
                if c == best_c:
                    ratio += " (faster peer)"
                if c.startswith("tomodem"):
                    ratio = f"**{ratio}**"
                sp = "–"
                if c == "tomodem-2t":
                    one = med(variant, N, "tomodem-1t", "pps")
                    sp = f"**{pps / one:.2f}×**" if one else "–"
                rss = med(variant, N, c, "rss_MB")
                out.append(f"| {LABEL.get(c, c)} | {N} | {pps:.3e} | {ratio} | {sp} | {rss:.1f} | {rss * 1024 / N:.2f} | "
                           f"{med(variant, N, c, 'pressure_Pa'):.4g} | {med(variant, N, c, 'Z'):.2f} | "
                           f"{med(variant, N, c, 'KE_J'):.3e} | {med(variant, N, c, 'rebuilds'):.0f} |")
        out.append("")
        if len(Ns) >= 2:
            lo, hi = Ns[0], Ns[-1]
            out.append(f"Marginal memory per particle, (RSS(N={hi}) − RSS(N={lo})) / {hi - lo}:\n")
            out.append("| code | marginal kB per particle | fixed part MB |")
            out.append("|---|---|---|")
            for c in ORDER:
                a, b = med(variant, lo, c, "rss_MB"), med(variant, hi, c, "rss_MB")
                if a is None or b is None:
                    continue
                per = (b - a) / (hi - lo)  # MB per particle
                out.append(f"| {LABEL.get(c, c)} | {per * 1024:.3f} | {a - per * lo:.1f} |")
            out.append("")
        # Spread of the repeats, to judge the noise.
        out.append("<details><summary>spread of the repeats (min–max particle-steps/s)</summary>\n")
        out.append("| code | N | min | max | runs |")
        out.append("|---|---|---|---|---|")
        for N in Ns:
            for c in ORDER:
                rs = cells.get((variant, N, c), [])
                if rs:
                    v = [float(r["pps"]) for r in rs]
                    out.append(f"| {c} | {N} | {min(v):.3e} | {max(v):.3e} | {len(v)} |")
        out.append("\n</details>\n")
    text = "\n".join(out)
    print(text)
    block = f"{BEGIN}\n{text}\n{END}"
    if os.path.exists(doc):
        old = open(doc).read()
        if BEGIN in old and END in old:
            new = old[:old.index(BEGIN)] + block + old[old.index(END) + len(END):]
        else:
            new = old.rstrip() + "\n\n" + block + "\n"
    else:
        new = "# Benchmarks\n\n" + block + "\n"
    open(doc, "w").write(new)


if __name__ == "__main__":
    main()
