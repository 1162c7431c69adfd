#!/usr/bin/env python3
"""Initial states of the peer benchmark scenes, written once and read by every code.

    make_state.py scene n OUTDIR [--v0 0.1] [--seed 12345]   ->  scene_n<N>.{data,txt}, N = n^3
    make_state.py gas   n OUTDIR [--v0 1.0] [--seed 4242]    ->  gas_n<N>.{data,txt},   N = 4 n^3
    make_state.py poly  n OUTDIR [--v0 0.1] [--seed 777]     ->  poly_n<N>.{data,txt}

scene: dense periodic Hertz-Mindlin state. A simple cubic lattice of n^3 spheres of diameter
       d = 1 mm in a periodic cube at solid fraction 0.55: the spacing s = d (pi/(6*0.55))^(1/3)
       = 0.9837 d is below d, so every neighbour pair overlaps by 1.6 % of d. Each coordinate is
       moved by a uniform random amount in +-0.015 d so that the overlaps differ.
gas:   dilute start of the dynamic variant. An FCC lattice of 4 n^3 spheres at the same solid
       fraction (cubic cell edge d (4 pi/(6*0.55))^(1/3); nearest neighbours about 10 % of d apart,
       so no contact at the start).
poly:  dense 1:10 bidisperse state (issue 19): n^3 large spheres (d = 1 mm) on the jittered
       lattice of `scene`, and small spheres (d = 0.1 mm) on a jittered simple cubic lattice ten
       times finer (same 1.6 % overlap of their own diameter) filling the space between them:
       a small sphere is kept when it overlaps no large sphere by more than 1.6 % of its own
       diameter. About half the volume is in each size; nearly every sphere touches its
       neighbours, so it times contact forces between and across the sizes (atom type 1 large,
       2 small: LAMMPS's `neighbor multi` bins the sizes apart).
All:   density 2500 kg/m^3; velocity components uniform in [-v0, v0], the mean removed so the
       total momentum is zero; no spin.

Files (SI units):
  <tag>_n<N>.data  LAMMPS/LIGGGHTS `read_data` file, atom style sphere/granular
                   (Atoms: id type diameter density x y z; Velocities: id vx vy vz wx wy wz)
  <tag>_n<N>.txt   line 1 "L d rho", then one sphere per line "x y z vx vy vz" (poly: "x y z vx vy vz d")
                   (read by the Yade script and by tomodem-bench-sceneA)

Pure Python (no NumPy); Python's Mersenne Twister with a fixed seed makes the files
reproducible on any machine.
"""
import argparse
import math
import os
import random

D = 1.0e-3      # sphere diameter, m
RHO = 2500.0    # density, kg/m^3
PHI = 0.55      # solid fraction
GROW = 1.03     # poly: diameters grown after placing (see poly_positions)


def scene_positions(n, rng):
    s = D * (math.pi / (6.0 * PHI)) ** (1.0 / 3.0)   # lattice spacing, one sphere per cube
    jitter = 0.015 * D
    pos = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                pos.append([(c + 0.5) * s + rng.uniform(-jitter, jitter) for c in (i, j, k)])
    return pos, n * s


def gas_positions(n):
    a = D * (4.0 * math.pi / (6.0 * PHI)) ** (1.0 / 3.0)   # FCC cubic cell, four spheres per cell
    basis = ((0.0, 0.0, 0.0), (0.5, 0.5, 0.0), (0.5, 0.0, 0.5), (0.0, 0.5, 0.5))
    pos = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                for b in basis:
                    pos.append([(c + bc + 0.25) * a for c, bc in zip((i, j, k), b)])
    return pos, n * a


def poly_positions(n, rng):
    """Large spheres as `scene`, then the small-sphere lattice in the space between them."""
    big, L = scene_positions(n, rng)
    ds = 0.1 * D
    s = ds * (math.pi / (6.0 * PHI)) ** (1.0 / 3.0)
    m = int(round(L / s))
    s = L / m                                      # fits the periodic box exactly
    overlap = ds - s                               # 1.6 % of ds
    jitter = 0.015 * ds
    cell = L / n                                   # one large sphere per cell of the coarse lattice
    keep = []
    reach = 0.5 * (D + ds) - overlap
    for i in range(m):
        for j in range(m):
            for k in range(m):
                p = [(c + 0.5) * s + rng.uniform(-jitter, jitter) for c in (i, j, k)]
                ci = [int(p[a] // cell) % n for a in range(3)]
                ok = True
                for di in (-1, 0, 1):              # the nearest large spheres: own and adjacent cells
                    for dj in (-1, 0, 1):
                        for dk in (-1, 0, 1):
                            q = big[((ci[0] + di) % n) * n * n + ((ci[1] + dj) % n) * n + (ci[2] + dk) % n]
                            r2 = 0.0
                            for a in range(3):
                                x = p[a] - q[a]
                                x -= L * round(x / L)
                                r2 += x * x
                            if r2 < reach * reach:
                                ok = False
                                break
                        if not ok:
                            break
                    if not ok:
                        break
                if ok:
                    keep.append(p)
    # Both lattices alone sit at the scene's solid fraction, so together they fill only about
    # 0.72 of the box, below the jamming point of the mixture: the spheres would rearrange into a
    # dense fluid (Z < 1 within 500 steps). Growing every diameter by GROW packs it to about 0.79
    # (overlaps 4.6 % of the own diameter), a jammed state that keeps its contacts.
    return big + keep, [D * GROW] * len(big) + [ds * GROW] * len(keep), L


def velocities(count, v0, rng):
    vel = [[rng.uniform(-v0, v0) for _ in range(3)] for _ in range(count)]
    mean = [sum(v[c] for v in vel) / count for c in range(3)]
    return [[v[c] - mean[c] for c in range(3)] for v in vel]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('tag', choices=('scene', 'gas', 'poly'))
    ap.add_argument('n', type=int, help='cells per edge (N = n^3 for scene, 4 n^3 for gas)')
    ap.add_argument('outdir')
    ap.add_argument('--v0', type=float, default=None, help='velocity amplitude, m/s')
    ap.add_argument('--seed', type=int, default=None)
    a = ap.parse_args()
    if a.n < 2:
        ap.error('n must be at least 2')
    v0 = a.v0 if a.v0 is not None else (1.0 if a.tag == 'gas' else 0.1)
    rng = random.Random(a.seed if a.seed is not None else {'scene': 12345, 'gas': 4242, 'poly': 777}[a.tag])
    if a.tag == 'poly':
        pos, diam, L = poly_positions(a.n, rng)
    else:
        pos, L = scene_positions(a.n, rng) if a.tag == 'scene' else gas_positions(a.n)
        diam = [D] * len(pos)
    vel = velocities(len(pos), v0, rng)
    N = len(pos)
    os.makedirs(a.outdir, exist_ok=True)
    stem = os.path.join(a.outdir, '%s_n%d' % (a.tag, N))
    with open(stem + '.data.tmp', 'w') as f:
        f.write('tomodem peer benchmark state %s, n = %d, solid fraction %.2f, d = %g m\n\n' % (a.tag, a.n, PHI, D))
        f.write('%d atoms\n%d atom types\n\n' % (N, 2 if a.tag == 'poly' else 1))
        for axis in 'xyz':
            f.write('0 %.10e %slo %shi\n' % (L, axis, axis))
        f.write('\nAtoms\n\n')
        for m, (p, d) in enumerate(zip(pos, diam), 1):
            f.write('%d %d %g %g %.10e %.10e %.10e\n' % (m, 1 if d > 0.5 * D else 2, d, RHO, p[0], p[1], p[2]))
        f.write('\nVelocities\n\n')
        for m, v in enumerate(vel, 1):
            f.write('%d %.10e %.10e %.10e 0 0 0\n' % (m, v[0], v[1], v[2]))
    with open(stem + '.txt.tmp', 'w') as f:
        f.write('%.10e %g %g\n' % (L, D, RHO))
        for p, v, d in zip(pos, vel, diam):
            # a seventh column (diameter) only where sizes differ
            extra = ' %g' % d if a.tag == 'poly' else ''
            f.write('%.10e %.10e %.10e %.10e %.10e %.10e%s\n' % (p[0], p[1], p[2], v[0], v[1], v[2], extra))
    os.replace(stem + '.data.tmp', stem + '.data')
    os.replace(stem + '.txt.tmp', stem + '.txt')
    print('%s: %d spheres, box edge %.6e m' % (stem, N, L))


if __name__ == '__main__':
    main()
