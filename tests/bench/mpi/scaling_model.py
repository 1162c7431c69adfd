#!/usr/bin/env python3
"""The scaling model of docs/scaling.md, from the measurements of run_scaling.sh.

usage: scaling_model.py MEASURED_DIR [--plots DIR] [--packing FILE.h5 ...]

MEASURED_DIR is run_scaling.sh's OUT (pingpong.csv, pingpong.load, results/ranks.csv; the scene
A state is made again with make_state.py when states/ is not there), e.g. tests/bench/mpi/measured,
the run docs/scaling.md quotes:
    python3 tests/bench/mpi/scaling_model.py tests/bench/mpi/measured --plots docs/images/scaling \
        --packing demo-out/green.h5
Prints the measured inputs, the halo check on real packings and the tables (markdown); with
--plots writes strong.png/.svg and weak.png/.svg there (gnuplot; scripts and data beside them).
Plain Python 3 (no numpy): the medians, fits and bounds are a few lines each.

The model, per rank and per DEM step, for P ranks each holding n = N/P particles of a periodic
box at number density rho, on a processor grid px x py x pz (near-cubic, as LAMMPS picks it):
    T(P) = t_p (n + f_g g) + m (alpha + beta b) + c ceil(log2 P) alpha
  g  ghosts: rho [(a + 2 r [px>1]) (b + 2 r [py>1]) (c + 2 r [pz>1]) - a b c] for a sub-domain a x b x c
  r  reach of a ghost: the largest contact distance plus the Verlet skin (d + 0.2 d)
  f_g  compute per ghost relative to an owned particle: 1/2 (a pair across the boundary is
       computed on both ranks, newton off; a ghost has about half its pairs with owned particles)
  m  messages per step: 2 per axis with more than one rank (the staged exchange of LAMMPS and of
     tomodem's decomposition: send to the left, receive from the right, then the other way)
  b  bytes per message: the ghosts of that axis' message x 72 bytes (x, v, omega as doubles)
  c  global reductions per step: 1 (the neighbour-list rebuild decision; the stress servo adds one)
T(1) = t_p N (the serial engine needs no ghosts). Speed-up S = T(1)/T(P), efficiency S/P; weak
scaling keeps n fixed: efficiency T_1rank(n)/T(P, n) with T_1rank(n) = t_p n.
The bounds of every prediction are the extremes over the corners of the measured ranges of t_p,
alpha and beta (min..max of the repeats), so they show the scatter of the inputs, not the model's
own error.
"""
import csv
import itertools
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile

BYTES_PER_GHOST = 72        # x, v, omega: 9 doubles
GHOST_WORK = 0.5            # f_g above
REDUCTIONS = 1              # c above
REACH_D = 1.2               # r / d: contact distance d plus the 0.2 d skin of scene A

# InfiniBand HDR (200 Gb/s = 25 GB/s per direction, "sub-600 nanosecond latency" for the
# ConnectX-6 adapter: Lenovo Press LP1195, cited in docs/scaling.md). MPI adds its software
# path on top of the adapter's latency, so the range runs from the adapter's 0.6 us to 1.5 us,
# and from the link's 25 GB/s down to 20 GB/s; the middle values are (median) 1.0 us, 23 GB/s.
IB_ALPHA = (1.0e-6, 0.6e-6, 1.5e-6)          # (typical, low, high) seconds per message
IB_BETA = (1 / 23e9, 1 / 25e9, 1 / 20e9)      # (typical, low, high) seconds per byte


def median_min_max(xs):
    return statistics.median(xs), min(xs), max(xs)


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


# ---- measured inputs -------------------------------------------------------------------------

def mpi_costs(rows):
    """alpha from the 0..64-byte ping-pongs, beta from the slope over 32 KiB .. 4 MiB (medians of
    the repeats; the range from the repeats' min and max)."""
    by = {}
    for r in rows:
        by.setdefault((r["kind"], int(r["bytes"])), []).append(float(r["seconds"]))
    small = [b for (k, b) in by if k == "pingpong" and b <= 64]
    alpha = [median_min_max(by[("pingpong", b)]) for b in small]
    a = (statistics.median(x[0] for x in alpha), min(x[1] for x in alpha), max(x[2] for x in alpha))
    large = sorted(b for (k, b) in by if k == "pingpong" and b >= 32768)

    def slope(pick):
        xs = large
        ys = [pick(by[("pingpong", b)]) for b in xs]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    beta = (slope(statistics.median), slope(min), slope(max))
    allreduce = median_min_max(by[("allreduce", 8)])
    halo = {b: median_min_max(v) for (k, b), v in by.items() if k == "halo"}
    pp = {b: median_min_max(v) for (k, b), v in by.items() if k == "pingpong"}
    return a, (beta[0], min(beta), max(beta)), allreduce, pp, halo


def scene_density(state):
    """Number density (per d^3), d and the box of a scene A state file ("L d rho" then x y z ...)."""
    with open(state) as f:
        box, d, _ = (float(x) for x in f.readline().split())
        pts = [tuple(float(x) for x in line.split()[:3]) for line in f if line.strip()]
    return len(pts) / (box / d) ** 3, d, box, pts


def h5_packing(path):
    """Positions, mean diameter and box of a tomodem packing (HDF5, read with h5dump)."""
    def data(name):
        text = subprocess.run(["h5dump", "-d", name, "-y", "-w", "0", path], capture_output=True, text=True,
                              check=True).stdout
        body = text[text.index("DATA {"):]
        body = body[:body.index("}")]
        return [float(x) for x in re.findall(r"[-+0-9.eE]+", body[6:])]
    pos, rad, h = data("/particles/position"), data("/particles/radius"), data("/cell/h")
    pts = [tuple(pos[3 * k:3 * k + 3]) for k in range(len(pos) // 3)]
    return pts, 2 * statistics.mean(rad), h[0]


def halo_check(pts, box, d, sides_d):
    """Ghosts counted around cubes of side s (in d) placed on a 3x3x3 grid of the periodic box,
    against the geometry: rho ((s + 2r)^3 - s^3). Returns rows (side, n, counted mean, formula)."""
    rho = len(pts) / box ** 3
    r = REACH_D * d
    rows = []
    for s_d in sides_d:
        s = s_d * d
        if s + 2 * r >= box:
            continue
        counts, owned = [], []
        for i, j, k in itertools.product(range(3), repeat=3):
            lo = (i * box / 3, j * box / 3, k * box / 3)
            inside = ghosts = 0
            for p in pts:
                u = [((p[a] - lo[a]) % box) for a in range(3)]              # 0..box from the cube's corner
                w = [x - box if x > box - r else x for x in u]              # ghosts just below the corner
                if all(0 <= x < s for x in u):
                    inside += 1
                elif all(-r <= x < s + r for x in w):
                    ghosts += 1
            counts.append(ghosts)
            owned.append(inside)
        rows.append((s_d, statistics.mean(owned), statistics.mean(counts), statistics.pstdev(counts),
                     rho * ((s + 2 * r) ** 3 - s ** 3)))
    return rows


# ---- the model -------------------------------------------------------------------------------

def grid(p):
    """The near-cubic px >= py >= pz with px py pz = p (least sub-domain surface for a cube)."""
    best = None
    for px in range(1, p + 1):
        if p % px:
            continue
        for py in range(1, p // px + 1):
            if (p // px) % py:
                continue
            pz = p // px // py
            surface = px * py + py * pz + px * pz
            if best is None or surface < best[0]:
                best = (surface, tuple(sorted((px, py, pz), reverse=True)))
    return best[1]


def step_time(N, P, rho, t_p, alpha, beta, r=REACH_D, newton=False):
    """Seconds per step on each of P ranks (lengths in d, rho per d^3). newton: each pair across
    a boundary computed once (a half list across ranks) and its force and torque sent back
    (reverse communication: as many messages again, 48 bytes per ghost), instead of twice."""
    if P == 1:
        return t_p * N
    side = (N / rho) ** (1 / 3)
    dims = grid(P)
    sub = [side / q for q in dims]
    grown = [s + (2 * r if q > 1 else 0) for s, q in zip(sub, dims)]
    g = rho * (grown[0] * grown[1] * grown[2] - sub[0] * sub[1] * sub[2])
    axes = sum(1 for q in dims if q > 1)
    messages = 2 * axes * (2 if newton else 1)
    comm = messages * alpha + beta * g * (BYTES_PER_GHOST + (48 if newton else 0))
    reduce = REDUCTIONS * math.ceil(math.log2(P)) * alpha
    return t_p * (N / P + (0 if newton else GHOST_WORK) * g) + comm + reduce


def bounded(f, ranges):
    """f at the medians, and its min and max over the corners of the (median, lo, hi) ranges."""
    mid = f(*(x[0] for x in ranges))
    corners = [f(*c) for c in itertools.product(*((x[1], x[2]) for x in ranges))]
    return mid, min(corners + [mid]), max(corners + [mid])


RANKS = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024]


def strong(N, rho, t_p, alpha, beta):
    rows = []
    for P in RANKS:
        eff = bounded(lambda t, a, b: step_time(N, 1, rho, t, a, b) / step_time(N, P, rho, t, a, b) / P,
                      [t_p, alpha, beta])
        rows.append((P, eff))
    return rows


def weak(n, rho, t_p, alpha, beta):
    rows = []
    for P in RANKS:
        eff = bounded(lambda t, a, b: step_time(n, 1, rho, t, a, b) / step_time(n * P, P, rho, t, a, b),
                      [t_p, alpha, beta])
        rows.append((P, eff))
    return rows


def fmt(x):
    return f"{x[0]:.3g} ({x[1]:.3g}–{x[2]:.3g})"


def plot(folder, name, title, ylabel, series):
    """series: list of (label, rows of (P, (mid, lo, hi)))."""
    os.makedirs(folder, exist_ok=True)
    dat = os.path.join(folder, name + ".dat")
    with open(dat, "w") as f:
        for label, rows in series:
            f.write(f"# {label}\n")
            for P, (m, lo, hi) in rows:
                f.write(f"{P} {m:.6g} {lo:.6g} {hi:.6g}\n")
            f.write("\n\n")
    plots = ", ".join(f"'{name}.dat' index {k} using 1:2:3:4 with yerrorlines linetype {k + 1} title '{label}' noenhanced"
                      for k, (label, _) in enumerate(series))
    # tomodem's one plot style (libs/core/share/plot_style.gp, also compiled into core's write_plot),
    # copied into the script so that it re-runs on its own: gnuplot NAME.gp.
    style = open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "libs", "core", "share",
                              "plot_style.gp")).read()
    gp = os.path.join(folder, name + ".gp")
    with open(gp, "w") as f:
        f.write(f"# {name}: made by tests/bench/mpi/scaling_model.py. Re-make: gnuplot {name}.gp, or\n"
                f"# gnuplot -e \"output_file='{name}.svg'\" {name}.gp\n{style}\n"
                f"if (!exists('output_file')) output_file = '{name}.png'\n"
                f"eval('set terminal ' . (output_file[strlen(output_file)-2:] eq 'svg' ? plot_terminal_svg : plot_terminal_png))\n"
                f"set output output_file\nset logscale x 2\nset xrange [0.8:1300]\n"
                f"set yrange [0:1.1]\nset key bottom left\nset xlabel 'MPI ranks (-)'\n"
                f"set ylabel '{ylabel}'\nset title '{title}' noenhanced\nplot {plots}\n")
    for ext in ("png", "svg"):
        subprocess.run(["gnuplot", "-e", f"output_file='{name}.{ext}'", name + ".gp"], cwd=folder, check=True)


def self_test():
    """Checks of the model's pieces against numbers worked out by hand (ctest runs it)."""
    import random
    failures = []

    def check(what, got, want, tol):
        ok = abs(got - want) <= tol
        print(f"{'ok  ' if ok else 'FAIL'} {what}: {got:.6g} (expected {want:.6g} +- {tol:.3g})")
        if not ok:
            failures.append(what)
    # The least-surface grids: 2 -> 2x1x1, 8 -> 2x2x2, 12 -> 3x2x2, 1024 -> 16x8x8.
    for p, want in ((2, (2, 1, 1)), (8, (2, 2, 2)), (12, (3, 2, 2)), (1024, (16, 8, 8))):
        check(f"grid({p}) == {want}", 0 if grid(p) == want else 1, 0, 0)
    # One rank: no ghosts, no messages: t_p N.
    check("T(1) = t_p N", step_time(8000, 1, 1.0, 1e-7, 1e-6, 1e-9), 8e-4, 1e-15)
    # 8 ranks, N = 8000 at rho = 1: box 20, sub-domains 10^3, g = 12.4^3 - 10^3 = 906.624;
    # free messages: T = t_p (1000 + g/2); then 6 messages, 3 reduction latencies, 72 g bytes.
    g = 12.4 ** 3 - 1000
    check("T(8), free network", step_time(8000, 8, 1.0, 1e-7, 0, 0), 1e-7 * (1000 + g / 2), 1e-15)
    check("T(8), alpha = 1 us, beta = 1 ns/B", step_time(8000, 8, 1.0, 1e-7, 1e-6, 1e-9),
          1e-7 * (1000 + g / 2) + 6e-6 + 72 * g * 1e-9 + 3e-6, 1e-15)
    check("T(8), newton on", step_time(8000, 8, 1.0, 1e-7, 1e-6, 1e-9, newton=True),
          1e-7 * 1000 + 12e-6 + 120 * g * 1e-9 + 3e-6, 1e-15)
    # alpha and beta from exact synthetic times t = 2 us + 1 ns/B x bytes.
    rows = [{"kind": k, "bytes": str(b), "seconds": str(2e-6 + 1e-9 * b)}
            for k in ("pingpong", "halo") for b in (0, 8, 64, 512, 4096, 32768, 262144, 1048576)]
    rows.append({"kind": "allreduce", "bytes": "8", "seconds": "1e-6"})
    a, b, _, _, _ = mpi_costs(rows)
    check("alpha from the small messages (median of 0, 8, 64 B)", a[0], 2e-6 + 8e-9, 1e-15)
    check("beta from the slope", b[0], 1e-9, 1e-18)
    # Ghosts of a Poisson point set (rho = 1.05 in a periodic box of 24): 27 cubes of side 4 on a
    # grid of pitch 8, so their shells (4 + 2.4 < 8) do not overlap and the counts are independent
    # Poisson draws of mean mu = rho((4 + 2.4)^3 - 4^3); the mean of 27 is within 4 sd, sqrt(mu/27).
    rng = random.Random(12345)
    box = 24.0
    pts = [(rng.uniform(0, box), rng.uniform(0, box), rng.uniform(0, box)) for _ in range(round(1.05 * box ** 3))]
    (side, _, mean, _, mu), = halo_check(pts, box, 1.0, [4])
    check("ghosts counted around a cube of side 4 d", mean, mu, 4 * math.sqrt(mu / 27))
    print(f"{'FAILED' if failures else 'OK'}: {len(failures)} failure(s)")
    return 1 if failures else 0


def main(argv):
    if "--self-test" in argv:
        sys.exit(self_test())
    if len(argv) < 2:
        sys.exit(__doc__)
    measured = argv[1]
    plots = argv[argv.index("--plots") + 1] if "--plots" in argv else None
    packings = [argv[k + 1] for k, a in enumerate(argv) if a == "--packing"]
    alpha, beta, allreduce, pp, halo = mpi_costs(read_csv(os.path.join(measured, "pingpong.csv")))
    with open(os.path.join(measured, "pingpong.load")) as f:
        pp_load = f.read().split()
    ranks = read_csv(os.path.join(measured, "results", "ranks.csv"))
    tom = [r for r in ranks if r["code"] == "tomodem"]
    N, steps = int(tom[0]["N"]), int(tom[0]["timed_steps"])
    t_p = median_min_max([float(r["cpu_s"]) / (N * steps) for r in tom])
    state = os.path.join(measured, "states", f"scene_n{N}.txt")
    if not os.path.exists(state):  # the committed measurements carry no state: make it (seeded, same file)
        tmp = tempfile.mkdtemp()
        here = os.path.dirname(os.path.abspath(__file__))
        subprocess.run([sys.executable, os.path.join(here, "..", "peers", "common", "make_state.py"), "scene",
                        str(round(N ** (1 / 3))), tmp], check=True, capture_output=True)
        state = os.path.join(tmp, f"scene_n{N}.txt")
    rho, d, box, pts = scene_density(state)

    print("## Measured inputs\n")
    print(f"- ping-pong and halo on 2 ranks, load average {pp_load[1]} before, {pp_load[3]} after")
    print(f"- alpha (one-way, 0-64 B) = {fmt(tuple(x * 1e6 for x in alpha))} us")
    print(f"- beta (slope 32 KiB-4 MiB) = {fmt(tuple(x * 1e9 for x in beta))} ns/B "
          f"= {1 / beta[0] / 1e9:.3g} GB/s")
    print(f"- allreduce of one double, 2 ranks = {fmt(tuple(x * 1e6 for x in allreduce))} us")
    print(f"- t_p (tomodem, scene A N={N}, 1 thread, CPU time) = {fmt(tuple(x * 1e9 for x in t_p))} ns "
          f"(loads {', '.join(r['load1'] for r in tom)})")
    print(f"- scene A: rho = {rho:.4f} / d^3 (solid fraction {rho * math.pi / 6:.3f}), reach r = {REACH_D} d\n")
    print("| bytes | ping-pong one-way us | halo exchange (both neighbours) us |")
    print("| ---: | --- | --- |")
    for b in sorted(pp):
        print(f"| {b} | {fmt(tuple(x * 1e6 for x in pp[b]))} | {fmt(tuple(x * 1e6 for x in halo[b]))} |")

    print("\n## Halo: counted against the geometry\n")
    print("| packing | cube side / d | owned n (mean) | ghosts counted (mean ± sd, 27 cubes) | rho((s+2r)^3 - s^3) | ratio |")
    print("| --- | ---: | ---: | --- | ---: | ---: |")
    checks = [("scene A state, N=%d" % N, pts, box / d, 1.0)]
    for path in packings:
        p, dm, L = h5_packing(path)
        checks.append((os.path.basename(path) + f", N={len(p)}", p, L / dm, dm))
    for label, p, L_d, scale in checks:
        pts_d = [tuple(x / scale for x in q) for q in p] if scale != 1.0 else [tuple(x / d for x in q) for q in p]
        for row in halo_check(pts_d, L_d, 1.0, [2, 4, 6, 8]):
            print(f"| {label} | {row[0]} | {row[1]:.1f} | {row[2]:.1f} ± {row[3]:.1f} | {row[4]:.1f} | "
                  f"{row[2] / row[4]:.3f} |")

    nets = [("shared memory (this machine, measured)", alpha, beta), ("InfiniBand HDR (published)", IB_ALPHA, IB_BETA)]
    print("\n## Strong scaling: parallel efficiency S/P (bounds from the measured scatter)\n")
    header = "| ranks | " + " | ".join(f"N=10^{e}, {n.split(' (')[0]}" for e in (6, 8) for n, _, _ in nets) + " |"
    print(header)
    print("| ---: |" + " --- |" * 4)
    tables = {(e, n): strong(10 ** e, rho, t_p, a, b) for e in (6, 8) for n, a, b in nets}
    for k, P in enumerate(RANKS):
        print(f"| {P} | " + " | ".join(fmt(tables[(e, n)][k][1]) for e in (6, 8) for n, _, _ in nets) + " |")
    print("\n## Weak scaling: efficiency T(1 rank, n)/T(P, n P)\n")
    per_rank = {6: 10 ** 6 / 1024, 8: 10 ** 8 / 1024}
    print("| ranks | " + " | ".join(f"n={per_rank[e]:.0f}/rank, {n.split(' (')[0]}" for e in (6, 8)
                                     for n, _, _ in nets) + " |")
    print("| ---: |" + " --- |" * 4)
    wtables = {(e, n): weak(per_rank[e], rho, t_p, a, b) for e in (6, 8) for n, a, b in nets}
    for k, P in enumerate(RANKS):
        print(f"| {P} | " + " | ".join(fmt(wtables[(e, n)][k][1]) for e in (6, 8) for n, _, _ in nets) + " |")

    print("\n## Newton off (pairs across a boundary on both ranks) against newton on (half list across ranks)\n")
    print("| ranks | N=10^6 IB, newton off | N=10^6 IB, newton on | ghosts per rank | owned per rank |")
    print("| ---: | --- | --- | ---: | ---: |")
    for P in RANKS:
        off = bounded(lambda t, a, b: step_time(10 ** 6, 1, rho, t, a, b) / step_time(10 ** 6, P, rho, t, a, b) / P,
                      [t_p, IB_ALPHA, IB_BETA])
        on = bounded(lambda t, a, b: step_time(10 ** 6, 1, rho, t, a, b) /
                     step_time(10 ** 6, P, rho, t, a, b, newton=True) / P, [t_p, IB_ALPHA, IB_BETA])
        side = (10 ** 6 / rho) ** (1 / 3)
        dims = grid(P)
        sub = [side / q for q in dims]
        grown = [x + (2 * REACH_D if q > 1 else 0) for x, q in zip(sub, dims)]
        g = rho * (grown[0] * grown[1] * grown[2] - sub[0] * sub[1] * sub[2])
        print(f"| {P} | {fmt(off)} | {fmt(on)} | {g:.0f} | {10 ** 6 / P:.0f} |")

    # LAMMPS on 1 and 2 ranks against the model with LAMMPS's own t_p.
    print("\n## LAMMPS scene A, 1 and 2 MPI ranks (granular, medians of the repeats)\n")
    print("| ranks | loop s (min–max) | CPU s (all ranks) | particle-steps/s | loads | model |")
    print("| ---: | --- | --- | --- | --- | --- |")
    lam = {P: [r for r in ranks if r["code"].startswith("lammps") and int(r["ranks"]) == P] for P in (1, 2)}
    loop1 = median_min_max([float(r["loop_s"]) for r in lam[1]])
    t_pl = tuple(x / (N * steps) for x in loop1)
    for P in (1, 2):
        loop = median_min_max([float(r["loop_s"]) for r in lam[P]])
        cpu = statistics.median(float(r["cpu_s"]) for r in lam[P])
        pred = bounded(lambda t, a, b: steps * step_time(N, P, rho, t, a, b), [t_pl, alpha, beta])
        print(f"| {P} | {fmt(loop)} | {cpu:.3g} | {N * steps / loop[0]:.3g} | "
              f"{', '.join(r['load1'] for r in lam[P])} | {fmt(pred)} s |")

    if plots:
        plot(plots, "scaling-strong", "Strong scaling (model, scene A density)", "parallel efficiency (-)",
             [(f"N=10^{e}, {n.split(' (')[0]}", tables[(e, n)]) for e in (6, 8) for n, _, _ in nets])
        plot(plots, "scaling-weak", "Weak scaling (model, scene A density)", "weak efficiency (-)",
             [(f"{per_rank[e]:.0f} per rank, {n.split(' (')[0]}", wtables[(e, n)]) for e in (6, 8) for n, _, _ in nets])


if __name__ == "__main__":
    main(sys.argv)
