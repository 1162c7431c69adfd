# Peer benchmark: a jammed packing at a pressure target (issue 19 item 2) with Yade 2023.02's
# periodic stress controller, the route Yade offers for this task. Run single-threaded:
#
#   yade -n -x -j1 pressure_target.py STATE PRESSURE [MAX_STEPS] [DAMPING] [STRAIN_PER_STEP] [SCALING] [CELL_MASS]
#
# STATE: "L" on line 1 (cube edge, m), then "x y z d" per sphere (m); tests/bench/pack/
# pressure_peers.sh writes it from the start of tomodem-pack's own run, so both codes start
# from the same spheres. PRESSURE in Pa. The material is the pressure-target bench input's:
# Hertz alumina (E = 380 GPa, nu = 0.22, rho = 3950 kg/m^3), no friction.
# The controller (PeriTriaxController, dynCell) moves the cell towards the target stress with at
# most STRAIN_PER_STEP (default 1e-3) of strain per step, Cundall's local damping DAMPING
# (default 0.4; Yade's own 0.2 took 21 % more steps on the 500-sphere tuning runs,
# docs/benchmarks.md) damps the particles, and SCALING (default 1) turns on Yade's density
# scaling (GlobalStiffnessTimeStepper + NewtonIntegrator.densityScaling: every particle's mass
# set so that its own critical step is the time step, as tomodem's stiffness-scaled masses).
# CELL_MASS (default 1): the cell's inertia as a multiple of Yade's default, the particles' mass.
# It stops, as tomodem-pack, when the unbalanced-force ratio (Yade's unbalancedForce: mean net
# force over mean contact force, tomodem's definition) is below 1e-4 and the stress within 1 %
# of the target, or after MAX_STEPS (default 2 000 000).
# Prints one "RESULT ..." line: steps, CPU and wall seconds, phi, Z, p/P, unbalanced, reached.
import math
import resource
import sys
import time

from yade import O, utils
from yade.wrapper import *

STATE, P = sys.argv[1], float(sys.argv[2])
MAX_STEPS = int(sys.argv[3]) if len(sys.argv) > 3 else 2000000
DAMPING = float(sys.argv[4]) if len(sys.argv) > 4 else 0.4
STRAIN_PER_STEP = float(sys.argv[5]) if len(sys.argv) > 5 else 1e-3
SCALING = int(sys.argv[6]) if len(sys.argv) > 6 else 1
CELL_MASS = float(sys.argv[7]) if len(sys.argv) > 7 else 1.0
CRITERION, STRESS_TOL = 1e-4, 0.01

cpu0, wall0 = time.process_time(), time.time()
with open(STATE) as f:
    edge = float(f.readline().split()[0])
    spheres = [[float(v) for v in line.split()] for line in f if line.strip()]
O.periodic = True
O.cell.setBox(edge, edge, edge)
alumina = O.materials.append(FrictMat(young=3.8e11, poisson=0.22, density=3950, frictionAngle=0.0))
O.bodies.append([utils.sphere(tuple(s[:3]), s[3] / 2, material=alumina) for s in spheres])
dt0 = 0.8 * utils.PWaveTimeStep()
done = [False]


def solid_fraction():
    return sum(4 / 3 * math.pi * b.shape.radius ** 3 for b in O.bodies) / O.cell.volume


def finished():
    done[0] = True
    O.pause()


O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()], verletDist=-0.2),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_MindlinPhys()],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    GlobalStiffnessTimeStepper(timestepSafetyCoefficient=0.8, timeStepUpdateInterval=10, defaultDt=dt0,
                               targetDt=dt0),
    PeriTriaxController(goal=(-P, -P, -P), stressMask=7, dynCell=True,
                        maxStrainRate=(STRAIN_PER_STEP / dt0,) * 3, maxUnbalanced=CRITERION,
                        relStressTol=STRESS_TOL, absStressTol=STRESS_TOL * P, doneHook='finished()',
                        mass=CELL_MASS * sum(b.state.mass for b in O.bodies)),
    NewtonIntegrator(damping=DAMPING, label='newton'),
]
newton.densityScaling = bool(SCALING)  # a property: it needs the time stepper in O.engines
O.dt = dt0
while not done[0] and O.iter < MAX_STEPS:
    O.run(min(20000, MAX_STEPS - O.iter), True)
    s = utils.getStress()
    print('step %d p/P %.4f unbalanced %.3e dt %.3e phi %.5f cpu %.1f' % (
        O.iter, -s.trace() / 3 / P, utils.unbalancedForce(), O.dt, solid_fraction(), time.process_time() - cpu0),
        flush=True)
s = utils.getStress()
p = -s.trace() / 3
phi = solid_fraction()
contacts = sum(1 for i in O.interactions if i.isReal and i.phys.normalForce.norm() > 0)
unbalanced = utils.unbalancedForce()
reached = unbalanced < CRITERION and abs(p / P - 1) < STRESS_TOL
print('RESULT code=yade n=%d steps=%d cpu=%.1f wall=%.1f phi=%.6f Z=%.3f p_over_P=%.5f unbalanced=%.3e '
      'reached=%d damping=%g strain_per_step=%g scaling=%d cell_mass=%g peak_rss_mb=%.0f' % (
          len(spheres), O.iter, time.process_time() - cpu0, time.time() - wall0, phi, 2.0 * contacts / len(spheres),
          p / P, unbalanced, int(reached), DAMPING, STRAIN_PER_STEP, SCALING, CELL_MASS,
          resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0), flush=True)
