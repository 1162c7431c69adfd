#!/usr/bin/env python3
"""The numbers of docs/rve.md (per-family tables, the N at which the replica CV meets the targets,
K_IC against W/d with its size-effect fits, CPU and memory per replica) from the RVE report's
summary.json and table.csv, as `tomodem run pipelines/rve.yaml` writes them to out/rve/report and
docs/rve/ keeps them. Run from the repository root: python3 tools/scripts/rve_tables.py [REPORT_DIR]."""
import csv, json, math, statistics, sys
from collections import defaultdict

d = sys.argv[1] if len(sys.argv) > 1 else 'docs/rve'
S = json.load(open(f'{d}/summary.json'))
rows = list(csv.DictReader(open(f'{d}/table.csv')))
PROPS = [('E_rel', 'E_iso/E_s', 1, 4, 0.02), ('young.nu_iso', 'ν_iso', 1, 3, None),
         ('fracture.K_IC', 'K_IC (kPa m^0.5)', 1e-3, 1, 0.05), ('sigma_rel', 'σ_x/σ_s', 1, 4, 0.02)]
FAMILIES = ['homogeneous', 'pore-former', 'aggregated']
cell = {(c['family'], int(float(c['particles'])), float(c['density']), c['property']): c for c in S['cells']}
sizes = sorted({k[1] for k in cell})
dens = sorted({k[2] for k in cell})
families = [f for f in FAMILIES if any(k[0] == f for k in cell)]
by = defaultdict(list)
for r in rows:
    by[(r['family'], int(float(r['particles'])), float(r['density']))].append(r)


def num(r, k):
    v = r.get(k, '')
    return float(v) if v not in ('', 'nan', None) else math.nan


def cv(c):
    return c['sd'] / abs(c['mean']) if c and c['n'] >= 2 else math.nan


def w_over_d(rs):
    """Crack-direction width over d, the diameter of a sphere of the solid volume per particle."""
    out = []
    for r in rs:
        V = num(r, 'fracture.width') * num(r, 'fracture.height') * num(r, 'fracture.thickness')
        dd = (6 * num(r, 'young.relative_density') * V / (math.pi * num(r, 'fracture.n_particles'))) ** (1 / 3)
        out.append(num(r, 'fracture.width') / dd)
    return statistics.mean(out) if out else math.nan


def linfit(x, y, w):
    """Weighted least squares y = a + b x; returns a, b, their sds and chi^2 (dof = n - 2)."""
    S0, Sx, Sy = sum(w), sum(wi * xi for wi, xi in zip(w, x)), sum(wi * yi for wi, yi in zip(w, y))
    Sxx, Sxy = sum(wi * xi * xi for wi, xi in zip(w, x)), sum(wi * xi * yi for wi, xi, yi in zip(w, x, y))
    D = S0 * Sxx - Sx * Sx
    a, b = (Sxx * Sy - Sx * Sxy) / D, (S0 * Sxy - Sx * Sy) / D
    chi2 = sum(wi * (yi - a - b * xi) ** 2 for wi, xi, yi in zip(w, x, y))
    return a, b, math.sqrt(Sxx / D), math.sqrt(S0 / D), chi2


for f in families:
    print(f'## {f}')
    print('| N | density | n | ' + ' | '.join(f'{lab} mean (CV)' for _, lab, *_ in PROPS) + ' | W/d |')
    print('|---|---|---|' + '---|' * (len(PROPS) + 1))
    for n in sizes:
        for x in dens:
            cs = [cell.get((f, n, x, p)) for p, *_ in PROPS]
            if not cs[0]:
                continue
            out = [f'{n}', f'{x:g}', str(cs[0]['n'])]
            for c, (_, _, scale, dig, _) in zip(cs, PROPS):
                out.append(f'{c["mean"] * scale:.{dig}f} ({100 * cv(c):.1f} %)')
            out.append(f'{w_over_d(by[(f, n, x)]):.1f}')
            print('| ' + ' | '.join(out) + ' |')
    print()

MIN_REPLICAS = 4  # a CV from fewer (marked †) is shown but decides nothing
print('## N at which the replica CV meets the target (E, σ 2 %, K_IC 5 %)')
print('| family | density | property | CV at ' + ' / '.join(str(n) for n in sizes) + ' | below from N | N* = N (CV/target)² |')
print('|---|---|---|---|---|---|')
for f in families:
    for x in dens:
        for p, lab, _, _, target in PROPS:
            if target is None:
                continue
            cs = [cell[(f, n, x, p)] for n in sizes if (f, n, x, p) in cell]
            shown = ' / '.join(f'{100 * cv(c):.1f} %' + ('†' if c['n'] < MIN_REPLICAS else '') for c in cs)
            # sizes with enough replicas for a CV: the smallest N from which every one is below the
            # target, and N* from the largest
            cvs = [(int(float(c['particles'])), cv(c)) for c in cs if c['n'] >= MIN_REPLICAS]
            first = next((str(n) for k, (n, _) in enumerate(cvs) if all(v < target for _, v in cvs[k:])), '—')
            n_big, v_big = cvs[-1]
            nstar = n_big * (v_big / target) ** 2
            print(f'| {f} | {x:g} | {lab.split(" ")[0]} | {shown} | {first} | {nstar:,.0f} from {n_big} |'.replace(',', ' '))
print()

print('## K_IC against W/d across the sizes (replica means weighted by 1/sem²)')
print('| family | density | W/d | K_IC ± sem (kPa m^0.5) | first-order K∞ (1 − c/W) | Bažant K∞ / √(1 + W0/W) |')
print('|---|---|---|---|---|---|')
for f in families:
    for x in dens:
        pts = []
        for n in sizes:
            c = cell.get((f, n, x, 'fracture.K_IC'))
            if c and c['n'] >= 2:
                pts.append((w_over_d(by[(f, n, x)]), c['mean'] / 1e3, c['sem'] / 1e3))
        if len(pts) < 3:
            continue
        W, K, s = zip(*pts)
        a, b, sa, sb, chi = linfit([1 / w for w in W], K, [1 / e ** 2 for e in s])
        first = f'{a:.0f} ± {sa:.0f} (c = {-b / a:.1f} d, χ² = {chi:.1f})'
        y = [1 / k ** 2 for k in K]
        sy = [2 * e / k ** 3 for k, e in zip(K, s)]
        a2, b2, sa2, _, chi2 = linfit([1 / w for w in W], y, [1 / e ** 2 for e in sy])
        if a2 > 0:
            kinf = a2 ** -0.5
            baz = f'{kinf:.0f} ± {0.5 * kinf * sa2 / a2:.0f} (W0 = {b2 / a2:.0f} d, χ² = {chi2:.1f})'
        else:
            baz = f'no finite K∞ (1/K∞² = {a2:.2e} ± {sa2:.1e})'
        print(f'| {f} | {x:g} | ' + ', '.join(f'{w:.1f}' for w in W) + ' | ' +
              ', '.join(f'{k:.0f} ± {e:.0f}' for k, e in zip(K, s)) + f' | {first} | {baz} |')
print()

print('## CPU (s) and peak memory (MB) per replica, mean over the replicas (0.6 / 0.8 for the measurements)')
print('| family | N | sinter | young | fracture | conduct | replica in all | peak RSS sinter / fracture |')
print('|---|---|---|---|---|---|---|---|')
for f in families:
    for n in sizes:
        r6, r8 = by.get((f, n, dens[0]), []), by.get((f, n, dens[-1]), [])
        if not r6:
            continue
        m = lambda rs, k: statistics.mean(num(r, k) for r in rs)
        sinter = m(r6, 'sinter.cpu_time_s')
        parts = {k: (m(r6, k), m(r8, k)) for k in ('young.cpu_time_s', 'fracture.cpu_time_s', 'conduct.cpu_time_s')}
        total = sinter + sum(a + b for a, b in parts.values())
        rss = (max(num(r, 'sinter.peak_rss_bytes') for r in r6) / 2**20, max(num(r, 'fracture.peak_rss_bytes') for r in r6 + r8) / 2**20)
        print(f'| {f} | {n} | {sinter:.1f} | ' + ' | '.join(f'{a:.2f} / {b:.2f}' for a, b in parts.values()) +
              f' | {total:.0f} | {rss[0]:.0f} / {rss[1]:.0f} |')
