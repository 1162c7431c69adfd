#!/usr/bin/env python3
"""The numbers of docs/study.md (its tables, rankings, targets, bounds, cost) from docs/study/summary.json and table.csv,
as printed by `tomodem run pipelines/study.yaml`. Run from the repository root: python3 tools/scripts/study_tables.py [REPORT_DIR]."""
import json, csv, math, sys, collections
d = sys.argv[1] if len(sys.argv) > 1 else 'docs/study'
S = json.load(open(f'{d}/summary.json'))
rows = list(csv.DictReader(open(f'{d}/table.csv')))
cells = {}
for c in S['cells']:
    cells[(c['family'], float(c['density']), c['property'])] = c
fams = []
for c in S['cells']:
    if c['family'] not in fams: fams.append(c['family'])
dens = sorted({float(c['density']) for c in S['cells']})
def g(f, x, p): return cells.get((f, x, p))
def fmt(v, sig=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)): return 'n/a'
    a = abs(v)
    if a == 0: return '0'
    digits = max(0, sig - 1 - int(math.floor(math.log10(a))))
    return f'{v:.{digits}f}'
def ci(c, scale=1, sig=3):
    if not c: return 'n/a'
    return f'{fmt(c["mean"]*scale, sig)} [{fmt(c["ci95"][0]*scale, sig)}, {fmt(c["ci95"][1]*scale, sig)}]'
def stop(c):
    s = c.get('stopped_because', '')
    return {'max reached': 'max', 'target met': 'target met', 'fixed replicas': 'fixed replicas'}.get(s, s)
print('## main table')
print('| family | route | density | n | stop | n_b/N | E/E_s [95 % CI] | ν | K_IC (kPa m^0.5) | K_IC/E (10⁻⁶ m^0.5) | σ/σ_s |')
print('|---|---|---|---|---|---|---|---|---|---|---|')
order = [f for f in fams if not f.endswith('-homothetic')]
order = order[:1] + [f for f in fams if f.endswith('-homothetic')] + order[1:]
for f in order:
    for x in dens:
        E = g(f, x, 'E_rel')
        if not E: continue
        route = 'homothetic' if f.endswith('-homothetic') else 'sintered'
        fam = f.replace('-homothetic', '')
        print(f'| {fam} | {route} | {x:g} | {E["n"]} | {stop(E)} | {g(f,x,"bonds_per_particle")["mean"]:.2f} | {ci(E)} | {ci(g(f,x,"young.nu_iso"),1,2)} | '
              f'{ci(g(f,x,"fracture.K_IC"),1e-3)} | {ci(g(f,x,"KIC_over_E"),1e6)} | {ci(g(f,x,"sigma_rel"))} |')
rk = collections.defaultdict(dict)
for r in S['rankings']:
    rk[(r['property'], r['at'])][frozenset((r['lower'], r['higher']))] = r
def pval(p):
    return 'p < 0.0001' if p < 1e-4 else f'p = {p:.2g}'
def pair(prop, x, a, b):
    return rk.get((prop, f'density={x:g}'), {}).get(frozenset((a, b)))
print('\n## route table (homogeneous sintered / homothetic)')
print('| density | E/E_s sintered / homothetic | Welch p | K_IC ratio | p | σ/σ_s ratio | p | n_b/N sintered / homothetic |')
print('|---|---|---|---|---|---|---|---|')
for x in dens:
    a, b = 'homogeneous', 'homogeneous-homothetic'
    if not g(b, x, 'E_rel'): continue
    out = [f'{x:g}']
    for p in ['E_rel', 'fracture.K_IC', 'sigma_rel']:
        r = pair(p, x, a, b)
        out += [f'{g(a,x,p)["mean"]/g(b,x,p)["mean"]:.2f}', pval(r['p']) + ('' if r['resolved'] else ' (not resolved)') if r else 'n/a']
    out.append(f'{g(a,x,"bonds_per_particle")["mean"]:.2f} / {g(b,x,"bonds_per_particle")["mean"]:.2f}')
    print('| ' + ' | '.join(out) + ' |')
print('\n## rankings (sintered families), resolved ones')
props = ['E_rel', 'fracture.K_IC', 'KIC_over_E', 'sigma_rel', 'young.nu_iso', 'bonds_per_particle']
sint = [f for f in fams if not f.endswith('-homothetic')]
for p in props:
    print(f'-- {p}')
    for x in dens:
        items = []
        for i in range(len(sint)):
            for j in range(i + 1, len(sint)):
                r = pair(p, x, sint[i], sint[j])
                if r: items.append(f'{r["lower"]}<{r["higher"]} {pval(r["p"])}{"" if r["resolved"] else " NR"}')
        print(f'  {x:g}: ' + '; '.join(items))
nres = sum(1 for r in S['rankings'] if r['resolved'])
print(f'rankings: {len(S["rankings"])}, resolved {nres}')
print('\n## targets (relative 95 % half-widths)')
met = 0
hw = collections.defaultdict(list)
for f in sint:
    for x in dens:
        E, s, K = g(f, x, 'E_rel'), g(f, x, 'sigma_rel'), g(f, x, 'fracture.K_IC')
        ok = E['rel_half_width95'] <= 0.02 and s['rel_half_width95'] <= 0.02 and K['rel_half_width95'] <= 0.05
        met += ok
        for k, c in (('E', E), ('s', s), ('K', K)): hw[k].append(c['rel_half_width95'])
        print(f'{f} {x:g}: n {E["n"]} {stop(E)}; E ±{100*E["rel_half_width95"]:.1f} %, σ ±{100*s["rel_half_width95"]:.1f} %, '
              f'K_IC ±{100*K["rel_half_width95"]:.1f} %, ν ±{100*g(f,x,"young.nu_iso")["rel_half_width95"]:.1f} % {"MET" if ok else "MISSED"}; cpu_s {E["cpu_s"]:.0f}')
print(f'met {met} of {len(sint)*len(dens)}; E {100*min(hw["E"]):.1f}-{100*max(hw["E"]):.1f} %, σ {100*min(hw["s"]):.1f}-{100*max(hw["s"]):.1f} %, K {100*min(hw["K"]):.1f}-{100*max(hw["K"]):.1f} %')
print('\n## literature (homogeneous sintered)')
f = 'homogeneous'
Ks = math.sqrt(2e11 * 2.0 / (1 - 0.09)) / 1e3
prev = None
lnE, lnK = [], []
for x in dens:
    E = g(f, x, 'E_rel'); K = g(f, x, 'fracture.K_IC')
    P = 1 - x
    a, b = (1 - P) ** 2, 1 - 1.9 * P + 0.9 * P * P
    print(f'| {x:g} | {ci(E)} | {a:.3f} | {E["mean"]/a:.2f} | {b:.3f} | {E["mean"]/b:.2f} |')
    lnE.append(math.log(E['mean'])); lnK.append(math.log(K['mean']))
for x in dens:
    E = g(f, x, 'E_rel'); K = g(f, x, 'fracture.K_IC')
    print(f'| {x:g} | {ci(K,1e-3)} | {K["mean"]/1e3/Ks:.3f} | {E["mean"]:.3f} | {K["mean"]/1e3/Ks/E["mean"]:.2f} |')
expo = [(lnE[i+1]-lnE[i])/(math.log(dens[i+1])-math.log(dens[i])) for i in range(len(dens)-1)]
print('local exponents d lnE/d ln rho:', ', '.join(f'{e:.1f}' for e in expo))
n = len(lnE); mx = sum(lnE)/n; my = sum(lnK)/n
slope = sum((a-mx)*(b-my) for a, b in zip(lnE, lnK)) / sum((a-mx)**2 for a in lnE)
print(f'K_IC ∝ E^{slope:.2f}; K_s = {Ks:.0f} kPa m^0.5')
print('\n## bounds (table.csv)')
def truth(v): return v.strip().lower() in ('true', '1', '1.0')
bx = [r for r in rows if truth(r.get('young.bound_exceeded', 'false'))]
cx = [r for r in rows if truth(r.get('conduct.bounds.bound_exceeded', 'false'))]
print(f'rows {len(rows)}; young bound exceeded {len(bx)}; conduct bound exceeded {len(cx)}')
for r in cx: print('  conduct', r['family'], r['density'], r['replica'], r['conduct.bounds.mean_sigma_over_sigma_s'], r['conduct.bounds.hs_upper_sigma_over_sigma_s'])
best = max(rows, key=lambda r: float(r['E_rel'])/float(r['young.hs_upper_E_over_Es']))
print(f'closest E to HS: {best["family"]} {best["density"]} r{best["replica"]}: {float(best["E_rel"])/float(best["young.hs_upper_E_over_Es"]):.3f} of bound')
bests = max(rows, key=lambda r: float(r['sigma_rel'])/float(r['conduct.bounds.hs_upper_sigma_over_sigma_s']))
print(f'closest sigma to HS: {bests["family"]} {bests["density"]} r{bests["replica"]}: {float(bests["sigma_rel"])/float(bests["conduct.bounds.hs_upper_sigma_over_sigma_s"]):.3f} of bound')
print('\n## cost (table.csv; pack/sinter once per family x replica)')
seen = set(); tot = collections.Counter(); cnt = collections.Counter(); per = collections.defaultdict(list)
for r in rows:
    key = (r['family'], r['replica'])
    route = r['route']
    if route == 'sintered' and key not in seen:
        seen.add(key)
        for st in ('pack', 'sinter'):
            v = r.get(f'{st}.cpu_time_s', '')
            if v: tot[st] += float(v); cnt[st] += 1; per[(st, r['family'])].append(float(v))
    for st in ('young', 'fracture', 'conduct', 'bond'):
        v = r.get(f'{st}.cpu_time_s', '')
        if v: tot[st + ('_h' if route == 'homothetic' else '')] += float(v); cnt[st + ('_h' if route == 'homothetic' else '')] += 1; per[(st, 'all')].append(float(v))
for k in tot: print(f'{k}: {cnt[k]} steps, {tot[k]:.1f} s CPU, {tot[k]/cnt[k]:.2f} per step')
for (st, fam), v in sorted(per.items()):
    if st == 'sinter': print(f'sinter {fam}: n {len(v)} {min(v):.1f}-{max(v):.1f} mean {sum(v)/len(v):.1f}')
print(f'fracture max {max(per[("fracture","all")]):.2f}')
print('tools total', f'{sum(tot.values()):.0f}')
print('\n## pore-former / homogeneous and per-bond')
for x in dens:
    a = g('homogeneous', x, 'E_rel'); b = g('pore-former', x, 'E_rel')
    ka = g('homogeneous', x, 'fracture.K_IC'); kb = g('pore-former', x, 'fracture.K_IC')
    za = g('homogeneous', x, 'bonds_per_particle')['mean']; zb = g('pore-former', x, 'bonds_per_particle')['mean']
    print(f'{x:g}: E pf/h {b["mean"]/a["mean"]:.2f}, K {kb["mean"]/ka["mean"]:.2f}, n_b/N {zb:.2f} vs {za:.2f}, E per n_b/N {b["mean"]/zb:.3f} vs {a["mean"]/za:.3f}')
