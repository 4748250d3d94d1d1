# yade_dang_meguid.py -- the Dang & Meguid (2010) sample built the usual YADE way, to time
# grainpack's DEM against (bench/bench_peers.py runs both and prints one table).
#
# The sample: a 0.5 m cube of spheres with the sieve of the paper's Table 2 (by weight),
# porosity 0.38, Table 1 material (E 15 MPa, ks/kn 0.5, friction 18 deg, density 2600, local
# damping 0.2; frictionless walls), stable at S_c <= 1e-4 (Eq. 7). The YADE way, after the
# triaxial tutorial (scripts/examples/triax-tutorial/script-session1.py), without gravity as
# there (with gravity on, the stress-controlled walls of this YADE ran through the sample, and
# a confining stress of the geostatic stress at the bottom stands in for it):
#   1. makeCloud with psdSizes / psdCumm and distributeMass=True (the mass-based PSD), as many
#      spheres as make the solid volume (1 - p) b^3 (Eq. 8 as corrected in NOTES.md), in a
#      loose cube;
#   2. isotropic compaction by the six walls of a TriaxialStressController (stress control,
#      no radius growth: the sizes stay those of the sieve) to the confining stress
#      rho g b (1 - p) (grainpack's top-wall stress), unbalanced force below 0.05;
#   3. friction lowered by 5 % steps while the porosity is above the target;
#   4. walls stopped, friction back to 18 deg, run until S_c <= 1e-4, S_c measured as grainpack
#      measures it: sum over spheres of |resultant| / sum over spheres of the sum of |f_n|
#      over their contacts.
# Run: yade -j1 -n -x bench/peers/yade_dang_meguid.py [seed [edge]] (edge: the cube's edge in m,
# 0.5 by default; a smaller one makes a quick check of the script). The last line of stdout is
# RESULT {json}; progress goes to stderr.
import json
import math
import sys
import time

from yade import pack, utils
from yade.wrapper import *  # noqa: F401,F403 (engines, materials: YADE's own namespace)

t_start = time.time()
cpu_start = time.process_time()
SEED = int(sys.argv[1]) if len(sys.argv) > 1 else 7
B = float(sys.argv[2]) if len(sys.argv) > 2 else 0.5  # sample edge (m)
POROSITY = 0.38
SIEVE_D = [0.010, 0.020, 0.050, 0.080, 0.100]  # Table 2, diameters (m)
SIEVE_W = [0.0, 0.02, 0.50, 0.95, 1.0]         # passing by weight
FRICTION = 18.0
YOUNG, POISSON, DENSITY, DAMPING = 15e6, 0.5, 2600.0, 0.2
GRAVITY = 9.81
SIGMA = DENSITY * GRAVITY * B * (1 - POROSITY)  # confining stress: the geostatic stress at the bottom
STABILITY = 1e-4
WALL = 0.05                  # wall thickness (m): thin walls let fast spheres through

def cloud(num, edge):
    sp = pack.SpherePack()
    sp.makeCloud((0, 0, 0), (edge, edge, edge), psdSizes=SIEVE_D, psdCumm=SIEVE_W,
                 distributeMass=True, num=num, porosity=0.6, seed=SEED)
    return sp

def solid(sp):
    return sum(4.0 / 3.0 * math.pi * r ** 3 for c, r in sp)

# 1. as many spheres as fill (1 - p) b^3 (sizes are deterministic for a given num)
vs_target = (1 - POROSITY) * B ** 3
edge0 = (vs_target / 0.25) ** (1.0 / 3.0)   # a loose cloud: solid fraction 0.25
num = 2000
for _ in range(4):
    sp = cloud(num, edge0)
    num = max(1, int(round(len(sp) * vs_target / solid(sp))))
sp = cloud(num, edge0)

O.materials.append(FrictMat(young=YOUNG, poisson=POISSON, frictionAngle=math.radians(FRICTION),
                            density=DENSITY, label='spheres'))
O.materials.append(FrictMat(young=YOUNG, poisson=POISSON, frictionAngle=0, density=0,
                            label='walls'))
walls = utils.aabbWalls([(0, 0, 0), (edge0, edge0, edge0)], thickness=WALL, material='walls')
wall_ids = O.bodies.append(walls)
sp.toSimulation(material='spheres')
spheres = [b for b in O.bodies if isinstance(b.shape, Sphere)]

triax = TriaxialStressController(thickness=WALL, stressMask=7, internalCompaction=False,
                                 max_vel=1.0)
triax.goal1 = triax.goal2 = triax.goal3 = -SIGMA
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_FrictPhys()],
                    [Law2_ScGeom_FrictPhys_CundallStrack()]),
    GlobalStiffnessTimeStepper(active=1, timeStepUpdateInterval=100, timestepSafetyCoefficient=0.8),
    triax,
    NewtonIntegrator(damping=DAMPING),
]

def note(phase):
    # progress on stderr (bench_peers.py reads only the RESULT line of stdout)
    sys.stderr.write("%7.1f s  step %7d  %-11s porosity %.4f  unbalanced %.3g\n" % (
        time.time() - t_start, O.iter, phase, porosity(), utils.unbalancedForce()))
    sys.stderr.flush()

def box_volume():
    return triax.width * triax.height * triax.depth

def porosity():
    return 1 - solid(sp_now()) / box_volume()

def sp_now():
    return [(b.state.pos, b.shape.radius) for b in spheres]

def stability():
    """Eq. 7 as grainpack computes it (gp_dem3d.h): sum |f_i| / sum_i sum_c |f_n|."""
    sum_f = 0.0
    for b in spheres:
        sum_f += O.forces.f(b.id).norm()
    sum_fn = 0.0
    for i in O.interactions:
        if not i.isReal:
            continue
        fn = i.phys.normalForce.norm()
        # a sphere pair counts for both spheres, a wall contact for its sphere
        sum_fn += fn * sum(1 for k in (i.id1, i.id2) if k not in wall_ids)
    return sum_f / sum_fn if sum_fn > 0 else float('inf')

# 2. isotropic compaction to the confining stress
while True:
    O.run(1000, True)
    note("compaction")
    if utils.unbalancedForce() < 0.05 and abs(SIGMA + triax.meanStress) / SIGMA < 0.01:
        break
porosity_compacted = porosity()
# 3. friction lowered while the porosity is above the target
phi = FRICTION
while porosity() > POROSITY and phi > 1e-3:
    phi *= 0.95
    utils.setContactFriction(math.radians(phi))
    O.run(500, True)
    note("friction %.2f" % phi)
phi_target = phi
# 4. walls stopped (zero strain rate), friction restored, until S_c <= 1e-4
triax.stressMask = 0
triax.goal1 = triax.goal2 = triax.goal3 = 0
utils.setContactFriction(math.radians(FRICTION))
sc = stability()
while sc > STABILITY and O.iter < 300000:  # a loose packing (too small an edge) never settles
    O.run(500, True)
    sc = stability()
    note("S_c %.2g" % sc)
elapsed = time.time() - t_start

# PSD by weight at the sieves, from the spheres as they end
d = [2 * r for c, r in sp_now()]
vol = sum(x ** 3 for x in d)
passing = [100.0 * sum(x ** 3 for x in d if x <= s) / vol for s in SIEVE_D]
psd_err = max(abs(p - 100.0 * w) for p, w in zip(passing, SIEVE_W))
res = {"time_s": elapsed, "cpu_s": time.process_time() - cpu_start, "spheres": len(spheres), "steps": O.iter, "dt": O.dt,
       "porosity": porosity(), "porosity_compacted": porosity_compacted,
       "friction_at_target_deg": phi_target, "stability": sc,
       "psd_passing_wt": passing, "psd_error_pp": psd_err,
       "box": [triax.width, triax.height, triax.depth], "threads": O.numThreads}
print("RESULT " + json.dumps(res), flush=True)
