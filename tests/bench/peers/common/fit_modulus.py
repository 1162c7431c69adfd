#!/usr/bin/env python3
"""Apparent Young's modulus of the bonded-lattice tension test.

    fit_modulus.py CURVE E_ANALYTIC [FRACTION]

CURVE has '#' comment lines and rows "strain stress_pulled stress_fixed" (Pa, tension
positive). The modulus is the least-squares slope of stress against strain over the rows whose
strain exceeds FRACTION (default 0.5) of the largest strain, which leaves out the start-up
transient. Prints one line of key=value pairs: E_pulled, E_fixed and their ratios to E_ANALYTIC.
"""
import sys


def slope(xs, ys):
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    e_ana = float(sys.argv[2])
    frac = float(sys.argv[3]) if len(sys.argv) == 4 else 0.5
    rows = []
    with open(sys.argv[1]) as f:
        for line in f:
            if line.strip() and not line.lstrip().startswith('#'):
                rows.append([float(v) for v in line.split()[:3]])
    top = max(r[0] for r in rows)
    used = [r for r in rows if r[0] > frac * top]
    if len(used) < 2:
        sys.exit('fit_modulus.py: fewer than two points above %.2f of the largest strain' % frac)
    strain = [r[0] for r in used]
    e_pulled = slope(strain, [r[1] for r in used])
    e_fixed = slope(strain, [r[2] for r in used])
    print('points=%d max_strain=%.4e E_pulled=%.6e E_fixed=%.6e E_ana=%.6e ratio_pulled=%.5f ratio_fixed=%.5f'
          % (len(used), top, e_pulled, e_fixed, e_ana, e_pulled / e_ana, e_fixed / e_ana))


if __name__ == '__main__':
    main()
