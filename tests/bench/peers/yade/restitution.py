# Peer benchmark: effective normal restitution of the scene-A contact model in Yade.
# Two spheres (d = 1 mm, rho = 2500, E = 1e8 Pa, nu = 0.25) meet head-on, each at speed V;
# requested e = 0.5. Prints "RESTITUTION code=yade V=<V> e=<e>".
#
#   yade -n -x -j1 restitution.py V
import math
import sys

from yade import O, utils
from yade.wrapper import *

V = float(sys.argv[1])
glass = O.materials.append(FrictMat(young=1.0e8, poisson=0.25, density=2500, frictionAngle=math.atan(0.5)))
left = O.bodies.append(utils.sphere((-5.5e-4, 0, 0), 0.5e-3, material=glass))
right = O.bodies.append(utils.sphere((5.5e-4, 0, 0), 0.5e-3, material=glass))
O.bodies[left].state.vel = Vector3(V, 0, 0)
O.bodies[right].state.vel = Vector3(-V, 0, 0)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_MindlinPhys(en=0.5, es=0.5)],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0),
]
O.dt = 1.35e-6
O.run(int(round(3 * 1.0e-4 / V / O.dt)) + 2000, True)
e = (O.bodies[right].state.vel[0] - O.bodies[left].state.vel[0]) / (2 * V)
print('RESTITUTION code=yade V=%g e=%.5f' % (V, e))
