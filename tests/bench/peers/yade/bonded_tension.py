# Peer benchmark: simple cubic lattice of bonded spheres in slow uniaxial tension, Yade 2023.02.
# n^3 spheres of radius R = 0.5 mm at spacing 2R; every touching pair is bonded (CohFrictMat with
# cohesion so large that nothing breaks). The layer at the lowest x is held, the layer at the
# highest x moves at constant speed so that the strain reaches EPS over 200 elastic-wave
# transits; lateral faces free. Expected: E = kn/(2R), nu = 0 (simple cubic lattice).
# Yade's cohesive stiffness is kn = 2 E1 R1 E2 R2/(E1 R1 + E2 R2) = young R for equal spheres, so
# young = 1e8 Pa gives kn = 5e4 N/m and E = young/2 = 5e7 Pa ("young" is a contact parameter).
# Writes bonded_yade_n<n>.dat ("strain stress_pulled stress_fixed", tension positive, strain over
# L0 = (n-1) 2R, stress = reaction force/(n 2R)^2) and prints a RESULT line.
#
#   yade -n -x -j1 bonded_tension.py n [EPS]
import math
import resource
import sys
import time

from yade import O, utils
from yade.wrapper import *

n = int(sys.argv[1])
EPS = float(sys.argv[2]) if len(sys.argv) > 2 else 1.0e-3
R, RHO, YOUNG = 0.5e-3, 2500.0, 1.0e8
kn = YOUNG * R
E_ana = kn / (2 * R)
L0, area = (n - 1) * 2 * R, (n * 2 * R) ** 2

start = time.time()
bond_mat = O.materials.append(CohFrictMat(young=YOUNG, poisson=0.3, density=RHO, frictionAngle=math.atan(0.5),
                                          isCohesive=True, normalCohesion=1e15, shearCohesion=1e15,
                                          momentRotationLaw=False))
grid = {}
for i in range(n):
    for j in range(n):
        for k in range(n):
            grid[i, j, k] = O.bodies.append(utils.sphere((2 * R * i, 2 * R * j, 2 * R * k), R, material=bond_mat))
fixed = [grid[0, j, k] for j in range(n) for k in range(n)]
pulled = [grid[n - 1, j, k] for j in range(n) for k in range(n)]

wave = math.sqrt(E_ana / (RHO * math.pi / 6))   # lattice mean density rho pi/6
t_load = 200 * L0 / wave
speed = EPS * L0 / t_load
for b in fixed + pulled:
    O.bodies[b].state.blockedDOFs = 'xyzXYZ'
    O.bodies[b].state.vel = Vector3(speed if b in pulled else 0.0, 0, 0)

# The spheres only touch: detect them with 1 % larger bounding boxes and interaction range in
# the first step, then go back to the exact sizes.
aabb = Bo1_Sphere_Aabb(aabbEnlargeFactor=1.01)
geom = Ig2_Sphere_Sphere_ScGeom6D(interactionDetectionFactor=1.01)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([aabb]),
    InteractionLoop([geom],
                    [Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=True, setCohesionOnNewContacts=False)],
                    [Law2_ScGeom6D_CohFrictPhys_CohesionMoment()]),
    NewtonIntegrator(damping=0.2),
]
O.dt = 0.2 * math.sqrt(O.bodies[0].state.mass / kn)
nsteps = int(t_load / O.dt)
O.step()
aabb.aabbEnlargeFactor = 1.0
geom.interactionDetectionFactor = 1.0
bonds = [I for I in O.interactions if I.isReal]
print('n=%d N=%d bonds=%d (lattice: %d) kn=%.6e (expected %.6e) dt=%.3e steps=%d'
      % (n, len(O.bodies), len(bonds), 3 * n * n * (n - 1), bonds[0].phys.kn, kn, O.dt, nsteps))

curve = []
chunk = max(1, nsteps // 200)
t1 = time.time()
for _ in range(0, nsteps, chunk):
    O.run(chunk, True)
    f_pulled = sum(O.forces.f(b)[0] for b in pulled)
    f_fixed = sum(O.forces.f(b)[0] for b in fixed)
    stretch = O.bodies[pulled[0]].state.pos[0] - O.bodies[fixed[0]].state.pos[0] - L0
    curve.append((stretch / L0, -f_pulled / area, f_fixed / area))
loop = time.time() - t1

with open('bonded_yade_n%d.dat' % n, 'w') as f:
    f.write('# strain stress_pulled stress_fixed\n')
    for row in curve:
        f.write('%.6e %.6e %.6e\n' % row)
broken = sum(1 for I in O.interactions if I.isReal and I.phys.cohesionBroken)
print('RESULT code=yade n=%d N=%d E_ana=%.6e final_strain=%.3e broken=%d steps=%d loop_wall=%.2f setup=%.2f maxrss_kB=%d'
      % (n, n ** 3, E_ana, curve[-1][0], broken, nsteps, loop, t1 - start,
         resource.getrusage(resource.RUSAGE_SELF).ru_maxrss))
