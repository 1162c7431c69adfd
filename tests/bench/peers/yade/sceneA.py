# Peer benchmark, scene A (dense periodic Hertz-Mindlin) and its gas variant, for Yade 2023.02
# (Debian bookworm). Run single-threaded:
#
#   yade -n -x -j1 sceneA.py N WARM STEPS [VERLET] [STATES] [TAG]
#
# N, WARM, STEPS: spheres, warm-up steps, timed steps. VERLET: InsertionSortCollider.verletDist
# (negative = fraction of the smallest radius per bounding-box side; -0.2 gives 0.1 d per side,
# i.e. a 0.2 d gap as the LAMMPS skin). STATES: folder of <TAG>_n<N>.txt (make_state.py).
# Prints "RESULT ... wall=<s> KE=<J> Z=<contacts per sphere> collider_runs=<n>" and
# "PRESSURE p=<Pa>" (Love-Weber stress of the contacts; Yade counts compression negative).
import math
import resource
import sys
import time

from yade import O, utils
from yade.wrapper import *

N, WARM, STEPS = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
VERLET = float(sys.argv[4]) if len(sys.argv) > 4 else -0.2
STATES = sys.argv[5] if len(sys.argv) > 5 else '../states'
TAG = sys.argv[6] if len(sys.argv) > 6 else 'scene'

start = time.time()
with open('%s/%s_n%d.txt' % (STATES, TAG, N)) as f:
    edge, diameter, density = (float(v) for v in f.readline().split())
    spheres = [[float(v) for v in line.split()] for line in f if line.strip()]

O.periodic = True
O.cell.setBox(edge, edge, edge)
glass = O.materials.append(FrictMat(young=1.0e8, poisson=0.25, density=density, frictionAngle=math.atan(0.5)))
ids = O.bodies.append([utils.sphere(tuple(s[:3]), diameter / 2, material=glass) for s in spheres])
for b, s in zip(ids, spheres):
    O.bodies[b].state.vel = Vector3(s[3], s[4], s[5])

# Hertz-Mindlin with damping from the restitution (en, es = 0.5); no numerical damping.
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()], verletDist=VERLET),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_MindlinPhys(en=0.5, es=0.5)],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0),
]
O.dt = 1.35e-6   # one tenth of the Rayleigh time


def kinetic_energy():
    return sum(0.5 * b.state.mass * b.state.vel.squaredNorm() for b in O.bodies)


def coordination():
    return 2.0 * sum(1 for i in O.interactions if i.isReal) / len(O.bodies)


print('set-up %.2f s' % (time.time() - start))
t0 = time.time()
O.run(WARM, True)
print('warm-up: %d steps in %.3f s, KE=%.6e Z=%.4f' % (WARM, time.time() - t0, kinetic_energy(), coordination()))
t1 = time.time()
O.run(STEPS, True)
wall = time.time() - t1
print('RESULT code=yade N=%d steps=%d wall=%.3f pps=%.4e KE=%.6e Z=%.4f collider_runs=%d verletDist=%g maxrss_kB=%d'
      % (N, STEPS, wall, N * STEPS / wall, kinetic_energy(), coordination(), O.engines[1].numAction, VERLET,
         resource.getrusage(resource.RUSAGE_SELF).ru_maxrss))
stress = utils.getStress()
print('PRESSURE p=%.6e Pa' % (-(stress[0, 0] + stress[1, 1] + stress[2, 2]) / 3))
