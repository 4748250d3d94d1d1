# yade_triaxial.py -- the judge of grainpack's `triaxial-3d`: the Dang & Meguid (2010)
# drained triaxial test ("Triaxial Tests", Fig. 7) run in YADE on the very same specimen.
#
#   yade -j1 -n -x bench/peers/yade_triaxial.py SPHERES BOX_JSON OUT_JSON
#        [--confining-kpa 50] [--axial-strain 0.2] [--strain-rate 0.01]
#        [--dt-safety 0.5] [--stability 1e-4] [--servo-tolerance 0.01]
#        [--max-consolidation-steps 2000000] [--check-every 200] [--samples 500]
#        [--wall-thickness 0.001] [--consolidation-rate RATE]
#
# SPHERES is grainpack's `export?format=yade` ("x y z r" a line, SI) and BOX_JSON has the box
# ({"lo": [..], "hi": [..]}, or {"box": [bx, by, bz]} from 0); bench/peers/triaxial_specimen.py
# writes both from a `spheres-3d` job. The spheres are loaded as they are (ymport.text: no
# re-generation, no shift), the six walls put exactly at the box faces.
#
# Model (Table 1 = YADE's stock TriaxialTest; NOTES.md "Dang & Meguid 2010: the triaxial tests"):
#   spheres FrictMat young 15e6, poisson (= ks/kn in YADE's Ip2_FrictMat_FrictMat_FrictPhys) 0.5,
#   friction 18 deg, density 2600; walls FrictMat young 15e6, poisson 0.2 (Table 1's "box
#   Poisson"), friction 0 (so their ks never acts), as TriaxialTest's boxes, 1 mm thick
#   (TriaxialTest's `thickness`), 1.5 x oversized in their plane (utils.aabbWalls); linear
#   Cundall-Strack law (Law2_ScGeom_FrictPhys_CundallStrack), NewtonIntegrator local damping 0.2
#   (forces and moments), gravity off, dt = dt_safety * PWaveTimeStep() fixed for the whole run.
# Walls, appended first: ids 0 x-, 1 x+, 2 y-, 3 y+, 4 z-, 5 z+. TriaxialStressController names
#   them left 0 / right 1 (its axis 1, goal1), bottom 2 / top 3 (axis 2, goal2) and back 4 /
#   front 5 (axis 3, goal3); stressMask bit 1 = x, 2 = y, 4 = z. The axial direction is z (the
#   deposition direction of grainpack's specimen): goal3, the back/front walls.
# 1. Isotropic consolidation: stressMask 7, goal1 = goal2 = goal3 = -sigma3 (YADE: tension
#    positive), internalCompaction False (the walls move, the radii stay), max_vel capped so
#    that the box closes no faster than --consolidation-rate (default: the strain rate), until
#    the six wall stresses are within --servo-tolerance (1 %) of sigma3 AND grainpack's S_c
#    (Eq. 7: sum over spheres |resultant| / sum over spheres of the sum of |f_n| of their
#    contacts, walls included) <= --stability (1e-4), checked every --check-every steps; else
#    it stops at --max-consolidation-steps and says so (stop_reason).
# 2. Drained axial loading: stressMask 3 (x and y walls hold sigma3), goal3 = -strain_rate
#    (TriaxialStressController moves each z wall at 0.5 * rate * depth: a constant true strain
#    rate, reached smoothly with its strainDamping 0.99), until the log axial strain reaches
#    --axial-strain. At most --samples points (the first at the end of consolidation).
# Measured as grainpack's spec says (compression positive, kPa): sigma1 = mean of the z walls'
#   force / current x*y area, sigma3 = mean of the four lateral walls' force / current area;
#   q = s1 - s3, p = (s1 + 2 s3) / 3; axial strain ln(H0/H), volumetric strain ln(V0/V) (both
#   from the wall positions, zero at the end of consolidation; positive = contraction);
#   porosity 1 - V_spheres / V_box (whole spheres); coordination: `coordination` = (2 sphere
#   contacts + wall contacts) / spheres (grainpack's coordination_number), `coordination_spheres`
#   = 2 sphere contacts / spheres, `coordination_mechanical` = Thornton's (2C - N1)/(N - N0 - N1)
#   with walls counted; `stability` = S_c; `unbalanced` = YADE's unbalancedForce();
#   `inertial_number` = rate * d50 * sqrt(density / p).
# Love-Weber stress at the end of consolidation (and at the start and end of the run), over the
#   TRUE box volume: `yade_getStress` = -utils.getStress(V) (YADE's own: the branch of a wall
#   contact runs to the wall box's centre, which adds about thickness / edge to the diagonal) and
#   `love_weber` = Eq. 15 with particles only (wall contacts: sphere centre to contact point),
#   which equals the wall stress at equilibrium.
# OUT_JSON: settings, specimen, initial state (vs grainpack's own stress), consolidation,
#   curves, peak {stress_ratio, axial_strain, phi_deg = asin((R-1)/(R+1)), q_kpa}, end,
#   volumetric_strain_at {0.05, 0.1, 0.2}, e50_mpa, dilatancy, servo_error_max, steps, dt,
#   wall_clock_s, cpu_s, yade_version. OUT_JSON.partial is rewritten every 25 samples while
#   running and removed at the end. Progress goes to stdout.
import argparse
import json
import math
import os
import shutil
import sys
import time

import yade
import yade.config
from yade import utils, ymport
from yade.wrapper import *  # noqa: F401,F403 (engines, materials: YADE's own namespace)

T0, CPU0 = time.time(), time.process_time()

ap = argparse.ArgumentParser(prog="yade -j1 -n -x yade_triaxial.py")
ap.add_argument("spheres")
ap.add_argument("box")
ap.add_argument("out")
ap.add_argument("--confining-kpa", type=float, default=50.0)
ap.add_argument("--axial-strain", type=float, default=0.2, help="log axial strain to reach")
ap.add_argument("--strain-rate", type=float, default=0.01, help="1/s")
ap.add_argument("--dt-safety", type=float, default=0.5, help="dt = this * PWaveTimeStep()")
ap.add_argument("--stability", type=float, default=1e-4, help="S_c to end consolidation")
ap.add_argument("--servo-tolerance", type=float, default=0.01,
                help="relative wall-stress error to end consolidation")
ap.add_argument("--max-consolidation-steps", type=int, default=2000000)
ap.add_argument("--check-every", type=int, default=200, help="steps between consolidation checks")
ap.add_argument("--consolidation-rate", type=float,
                help="1/s: cap of the walls' strain rate while consolidating "
                     "(default: --strain-rate)")
ap.add_argument("--samples", type=int, default=500)
ap.add_argument("--wall-thickness", type=float, default=0.001, help="m (TriaxialTest's 0.001)")
ap.add_argument("--friction-deg", type=float, default=18.0)
ap.add_argument("--young", type=float, default=15e6)
ap.add_argument("--poisson", type=float, default=0.5, help="YADE's poisson = ks/kn")
ap.add_argument("--density", type=float, default=2600.0)
ap.add_argument("--damping", type=float, default=0.2)
A = ap.parse_args(sys.argv[1:])

SIGMA3 = A.confining_kpa * 1e3  # Pa, compression positive
THICK = A.wall_thickness
LEFT, RIGHT, BOTTOM, TOP, BACK, FRONT = 0, 1, 2, 3, 4, 5  # x-, x+, y-, y+, z-, z+


def say(msg):
    print("%8.1f s  it %8d  %s" % (time.time() - T0, O.iter, msg), flush=True)


def finite(x):
    """JSON has no NaN or infinity: null instead."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite(v) for v in x]
    return x


def write_json(path, obj):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(finite(obj), f, indent=1, allow_nan=False)
    os.replace(tmp, path)


# ---------------------------------------------------------------- the specimen and the box
with open(A.box) as f:
    boxinfo = json.load(f)
if "lo" in boxinfo and "hi" in boxinfo:
    LO, HI = [float(v) for v in boxinfo["lo"]], [float(v) for v in boxinfo["hi"]]
else:
    LO, HI = [0.0, 0.0, 0.0], [float(v) for v in boxinfo["box"]]

O.materials.append(FrictMat(young=A.young, poisson=A.poisson, density=A.density,
                            frictionAngle=math.radians(A.friction_deg), label="spheres"))
O.materials.append(FrictMat(young=A.young, poisson=0.2, density=0, frictionAngle=0,
                            label="walls"))
wall_ids = O.bodies.append(utils.aabbWalls([tuple(LO), tuple(HI)], thickness=THICK,
                                           oversizeFactor=1.5, material="walls"))
assert list(wall_ids) == [0, 1, 2, 3, 4, 5], wall_ids
sphere_ids = O.bodies.append(ymport.text(A.spheres, material="spheres"))
SPHERES = [O.bodies[i] for i in sphere_ids]
N = len(SPHERES)
RADII = [b.shape.radius for b in SPHERES]
V_SOLID = sum(4.0 / 3.0 * math.pi * r ** 3 for r in RADII)
V_BOX0 = (HI[0] - LO[0]) * (HI[1] - LO[1]) * (HI[2] - LO[2])


def d50_by_mass():
    d = sorted(2 * r for r in RADII)
    w = [x ** 3 for x in d]
    tot, acc = sum(w), 0.0
    for x, wi in zip(d, w):
        acc += wi
        if acc >= 0.5 * tot:
            return x
    return d[-1]


D50 = d50_by_mass()
# loaded exactly? (ymport.text parses the %.17g text with float(): bit for bit)
with open(A.spheres) as f:
    rows = [[float(v) for v in l.split()[:4]] for l in f if l.strip() and not l.startswith("#")]
load_err = max(max(abs(b.state.pos[k] - r[k]) for k in range(3)) + abs(b.shape.radius - r[3])
               for b, r in zip(SPHERES, rows))
assert len(rows) == N and load_err == 0.0, (len(rows), N, load_err)

triax = TriaxialStressController(
    thickness=THICK, internalCompaction=False, stressMask=7,
    wall_left_id=LEFT, wall_right_id=RIGHT, wall_bottom_id=BOTTOM, wall_top_id=TOP,
    wall_back_id=BACK, wall_front_id=FRONT, label="triax")
triax.goal1 = triax.goal2 = triax.goal3 = -SIGMA3
CONS_RATE = A.consolidation_rate if A.consolidation_rate is not None else A.strain_rate
MAX_VEL_AXIAL = triax.max_vel  # YADE's default, 1 m/s
triax.max_vel = 0.5 * CONS_RATE * sum(HI[k] - LO[k] for k in range(3)) / 3  # see 1. below
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Box_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_FrictPhys()],
                    [Law2_ScGeom_FrictPhys_CundallStrack()]),
    triax,
    NewtonIntegrator(damping=A.damping, gravity=(0, 0, 0)),
]
PWAVE = utils.PWaveTimeStep()
O.dt = A.dt_safety * PWAVE


# ---------------------------------------------------------------- measurements
def dims():
    p = [O.bodies[i].state.pos for i in range(6)]
    return (p[RIGHT][0] - p[LEFT][0] - THICK, p[TOP][1] - p[BOTTOM][1] - THICK,
            p[FRONT][2] - p[BACK][2] - THICK)


def wall_stresses():
    """The six walls' normal stresses (Pa, compression positive) over the current face areas,
    in the order x-, x+, y-, y+, z-, z+."""
    lx, ly, lz = dims()
    ax, ay, az = ly * lz, lx * lz, lx * ly
    f = [O.forces.f(i, sync=True) for i in range(6)]
    return [-f[LEFT][0] / ax, f[RIGHT][0] / ax, -f[BOTTOM][1] / ay, f[TOP][1] / ay,
            -f[BACK][2] / az, f[FRONT][2] / az]


def contact_state(tensor=False):
    """S_c, coordination numbers, contact counts and (tensor=True) the Love-Weber stress sum
    (particles only; compression positive, not yet divided by the volume)."""
    sum_fn = 0.0
    nss = nsw = 0
    count = {}
    s = [[0.0] * 3 for _ in range(3)]
    for i in O.interactions:
        if not i.isReal:
            continue
        fnv = i.phys.normalForce
        fn = fnv.norm()
        if fn <= 0:
            continue
        a, b = i.id1, i.id2
        wa, wb = a < 6, b < 6
        if wa and wb:
            continue
        count[a] = count.get(a, 0) + 1
        count[b] = count.get(b, 0) + 1
        if not wa and not wb:
            nss += 1
            sum_fn += 2 * fn
        else:
            nsw += 1
            sum_fn += fn
        if tensor:
            F = fnv + i.phys.shearForce  # the force on id2
            if not wa and not wb:
                l = O.bodies[a].state.pos - O.bodies[b].state.pos
                fo = F
            else:
                sid = b if wa else a
                l = i.geom.contactPoint - O.bodies[sid].state.pos
                fo = F if sid == b else -F  # the force on the sphere
            for r in range(3):
                for c in range(3):
                    s[r][c] -= fo[r] * l[c]
    sum_f = sum(O.forces.f(b.id, sync=True).norm() for b in SPHERES)
    counts = [count.get(b.id, 0) for b in SPHERES]
    n0 = sum(1 for c in counts if c == 0)
    n1 = sum(1 for c in counts if c == 1)
    c_all = sum(counts)  # = 2 nss + nsw
    out = {"stability": sum_f / sum_fn if sum_fn > 0 else float("inf"),
           "coordination": c_all / N, "coordination_spheres": 2.0 * nss / N,
           "coordination_mechanical": (c_all - n1) / (N - n0 - n1) if N - n0 - n1 > 0 else 0.0,
           "contacts": nss, "wall_contacts": nsw, "rattlers_0": n0, "rattlers_1": n1}
    if tensor:
        out["lw_sum"] = s
    return out


def stresses_at_equilibrium(label):
    """Wall stresses beside the two Love-Weber tensors over the true box volume (kPa)."""
    lx, ly, lz = dims()
    vol = lx * ly * lz
    cs = contact_state(tensor=True)
    lw = [[0.5 * (cs["lw_sum"][r][c] + cs["lw_sum"][c][r]) / vol / 1e3 for c in range(3)]
          for r in range(3)]
    g = utils.getStress(vol)
    gy = [[-0.5 * (g[r, c] + g[c, r]) / 1e3 for c in range(3)] for r in range(3)]
    ws = wall_stresses()
    wall = [0.5 * (ws[0] + ws[1]) / 1e3, 0.5 * (ws[2] + ws[3]) / 1e3, 0.5 * (ws[4] + ws[5]) / 1e3]
    rel = lambda m: [(m[k][k] - wall[k]) / wall[k] if wall[k] else None for k in range(3)]
    res = {"at": label, "iter": O.iter, "box": [lx, ly, lz], "volume": vol,
           "wall_kpa": wall, "wall_each_kpa": [w / 1e3 for w in ws],
           "love_weber_kpa": lw, "yade_getStress_kpa": gy,
           "love_weber_vs_wall": rel(lw), "yade_getStress_vs_wall": rel(gy),
           "stability": cs["stability"], "unbalanced": utils.unbalancedForce(),
           "coordination": cs["coordination"], "porosity": 1 - V_SOLID / vol}
    return res


# ---------------------------------------------------------------- initial state (step 1)
O.step()  # interactions are created and their forces computed from the loaded positions
init = stresses_at_equilibrium("initial")
gp = (boxinfo.get("grainpack") or {})
if gp.get("stress"):
    init["grainpack_stress_kpa"] = [[v / 1e3 for v in row] for row in gp["stress"]]
init["note"] = ("YADE starts with no shear force history (only the normal forces of the "
                "loaded overlaps), and gravity is off here, on under grainpack")
say("loaded %d spheres (exactly: max |diff| %g), box %s..%s, dt %.4g (PWave %.4g x %.2f), "
    "d50 %.4g m; initial wall stresses %s kPa, S_c %.3g" % (
        N, load_err, LO, HI, O.dt, PWAVE, A.dt_safety, D50,
        ["%.2f" % w for w in init["wall_each_kpa"]], init["stability"]))

settings = {
    "dt": O.dt, "pwave_dt": PWAVE, "dt_safety": A.dt_safety, "damping": A.damping,
    "gravity": [0, 0, 0], "threads": O.numThreads,
    "sphere_material": {"class": "FrictMat", "young": A.young, "poisson_ks_over_kn": A.poisson,
                        "friction_deg": A.friction_deg, "density": A.density},
    "wall_material": {"class": "FrictMat", "young": A.young, "poisson_ks_over_kn": 0.2,
                      "friction_deg": 0.0, "density": 0.0},
    "contact_law": "Ip2_FrictMat_FrictMat_FrictPhys + Law2_ScGeom_FrictPhys_CundallStrack "
                   "(kn = 2 E1 r1 E2 r2 / (E1 r1 + E2 r2), ks = kn * ks/kn)",
    "walls": {"ids": {"x-": LEFT, "x+": RIGHT, "y-": BOTTOM, "y+": TOP, "z-": BACK, "z+": FRONT},
              "triax_names": {"left": LEFT, "right": RIGHT, "bottom": BOTTOM, "top": TOP,
                              "back": BACK, "front": FRONT},
              "thickness": THICK, "oversize_factor": 1.5, "lo": LO, "hi": HI,
              "axial_axis": "z (goal3; back/front walls)"},
    "servo": {"class": "TriaxialStressController", "internalCompaction": False,
              "consolidation": {"stressMask": 7, "goal": -SIGMA3},
              "axial": {"stressMask": 3, "goal1": -SIGMA3, "goal2": -SIGMA3,
                        "goal3": -A.strain_rate},
              "stressDamping": triax.stressDamping, "strainDamping": triax.strainDamping,
              "max_vel": triax.max_vel, "stiffnessUpdateInterval": triax.stiffnessUpdateInterval,
              "computeStressStrainInterval": triax.computeStressStrainInterval},
    "consolidation_stop": {"servo_tolerance": A.servo_tolerance, "stability": A.stability,
                           "check_every": A.check_every,
                           "max_steps": A.max_consolidation_steps},
    "confining_kpa": A.confining_kpa, "axial_strain": A.axial_strain,
    "strain_rate": A.strain_rate, "samples": A.samples,
}
result = {"yade_version": yade.config.version, "script": os.path.abspath(sys.argv[0]),
          "status": "running", "inputs": {"spheres": os.path.abspath(A.spheres),
                                          "box": os.path.abspath(A.box), "job": boxinfo.get("job")},
          "settings": settings,
          "specimen": {"spheres": N, "solid_volume": V_SOLID, "d50_by_mass": D50,
                       "r_min": min(RADII), "r_max": max(RADII),
                       "porosity": 1 - V_SOLID / V_BOX0,
                       "grainpack": gp},
          "initial": init}

# ---------------------------------------------------------------- 1. isotropic consolidation
# The servo moves a wall by (force error / stiffness of its contacts), capped at max_vel * dt;
# YADE's default cap (1 m/s, an isotropic strain rate near 2 / edge per second) slams a loose
# specimen shut in a few hundred steps. Capped here so that the box closes no faster than at
# the consolidation rate (each wall at 0.5 * rate * edge); the cap goes back to YADE's 1 m/s
# for the axial loading (where it never binds at these rates).
settings["servo"]["consolidation"].update({"rate_cap": CONS_RATE, "max_vel": triax.max_vel})
settings["servo"]["axial"]["max_vel"] = MAX_VEL_AXIAL
t_c, cpu_c = time.time(), time.process_time()
history = []
stop = None
while True:
    O.run(A.check_every, True)
    ws = wall_stresses()
    err = max(abs(w - SIGMA3) for w in ws) / SIGMA3
    unb = utils.unbalancedForce()
    sc = contact_state()["stability"] if err <= A.servo_tolerance else float("nan")
    lx, ly, lz = dims()
    history.append([O.iter, err, unb, sc, 1 - V_SOLID / (lx * ly * lz)])
    if len(history) % 25 == 1 or (err <= A.servo_tolerance and sc <= A.stability):
        say("consolidation: wall error %.4f, unbalanced %.3g, S_c %.3g, porosity %.4f" % (
            err, unb, sc, history[-1][4]))
    if err <= A.servo_tolerance and sc <= A.stability:
        stop = "stable"
        break
    if O.iter >= A.max_consolidation_steps:
        stop = "max_steps"
        say("consolidation stopped at the step cap: S_c %.3g > %g or wall error %.4f > %g"
            % (sc, A.stability, err, A.servo_tolerance))
        break
cons = stresses_at_equilibrium("end of consolidation")
cons.update({"stop_reason": stop, "steps": O.iter, "sim_time_s": O.time,
             "wall_clock_s": time.time() - t_c, "cpu_s": time.process_time() - cpu_c,
             "wall_error_max": max(abs(w - SIGMA3 * 1e-3) for w in cons["wall_each_kpa"])
             / (SIGMA3 * 1e-3)})
cons.update({k: v for k, v in contact_state().items() if k != "stability"})
step = max(1, len(history) // 500)
cons["history"] = {"columns": ["iter", "wall_error", "unbalanced", "stability", "porosity"],
                   "rows": history[::step] + ([history[-1]] if (len(history) - 1) % step else [])}
result["consolidation"] = cons
say("consolidated (%s) in %d steps, %.1f s: walls %s kPa, Love-Weber diag %s (vs wall %s), "
    "YADE getStress diag %s, porosity %.4f" % (
        stop, O.iter, cons["wall_clock_s"], ["%.3f" % w for w in cons["wall_each_kpa"]],
        ["%.3f" % cons["love_weber_kpa"][k][k] for k in range(3)],
        ["%+.2f%%" % (100 * v) for v in cons["love_weber_vs_wall"]],
        ["%.3f" % cons["yade_getStress_kpa"][k][k] for k in range(3)], cons["porosity"]))

# ---------------------------------------------------------------- 2. drained axial loading
L0 = dims()
V0 = L0[0] * L0[1] * L0[2]
iter0, time0 = O.iter, O.time
t_a, cpu_a = time.time(), time.process_time()
COLS = ["axial_strain", "volumetric_strain", "lateral_strain_x", "lateral_strain_y",
        "sigma1_kpa", "sigma3_kpa", "sigma_x_kpa", "sigma_y_kpa", "q_kpa", "p_kpa",
        "stress_ratio", "servo_error", "coordination", "coordination_spheres",
        "coordination_mechanical", "porosity", "stability", "unbalanced", "inertial_number",
        "iter", "time_s"]
curves = {c: [] for c in COLS}


def sample():
    lx, ly, lz = dims()
    ws = wall_stresses()
    s1 = 0.5 * (ws[4] + ws[5])
    sx, sy = 0.5 * (ws[0] + ws[1]), 0.5 * (ws[2] + ws[3])
    s3 = 0.5 * (sx + sy)
    cs = contact_state()
    p = (s1 + 2 * s3) / 3
    row = {"axial_strain": math.log(L0[2] / lz),
           "volumetric_strain": math.log(V0 / (lx * ly * lz)),
           "lateral_strain_x": math.log(L0[0] / lx), "lateral_strain_y": math.log(L0[1] / ly),
           "sigma1_kpa": s1 / 1e3, "sigma3_kpa": s3 / 1e3, "sigma_x_kpa": sx / 1e3,
           "sigma_y_kpa": sy / 1e3, "q_kpa": (s1 - s3) / 1e3, "p_kpa": p / 1e3,
           "stress_ratio": s1 / s3 if s3 > 0 else float("nan"),
           "servo_error": max(abs(w - SIGMA3) for w in ws[:4]) / SIGMA3,
           "coordination": cs["coordination"], "coordination_spheres": cs["coordination_spheres"],
           "coordination_mechanical": cs["coordination_mechanical"],
           "porosity": 1 - V_SOLID / (lx * ly * lz), "stability": cs["stability"],
           "unbalanced": utils.unbalancedForce(),
           "inertial_number": A.strain_rate * D50 * math.sqrt(A.density / p) if p > 0 else None,
           "iter": O.iter - iter0, "time_s": O.time - time0}
    for c in COLS:
        curves[c].append(row[c])
    return row


def interp(xs, ys, x):
    for k in range(1, len(xs)):
        if xs[k] >= x:
            x0, x1 = xs[k - 1], xs[k]
            return ys[k] if x1 == x0 else ys[k - 1] + (ys[k] - ys[k - 1]) * (x - x0) / (x1 - x0)
    return None


def summary():
    e, R, q = curves["axial_strain"], curves["stress_ratio"], curves["q_kpa"]
    out = {}
    if len(e) < 2:
        return out
    k = max(range(1, len(R)), key=lambda j: R[j])
    Rp = R[k]
    out["peak"] = {"stress_ratio": Rp, "axial_strain": e[k], "q_kpa": q[k],
                   "sigma1_kpa": curves["sigma1_kpa"][k], "volumetric_strain":
                   curves["volumetric_strain"][k],
                   "phi_deg": math.degrees(math.asin((Rp - 1) / (Rp + 1)))}
    Re = R[-1]
    out["end"] = {"stress_ratio": Re, "axial_strain": e[-1], "q_kpa": q[-1],
                  "volumetric_strain": curves["volumetric_strain"][-1],
                  "phi_deg": math.degrees(math.asin((Re - 1) / (Re + 1))),
                  "coordination": curves["coordination"][-1],
                  "porosity": curves["porosity"][-1]}
    out["volumetric_strain_at"] = {str(x): interp(e, curves["volumetric_strain"], x)
                                   for x in (0.05, 0.1, 0.2)}
    out["stress_ratio_at"] = {str(x): interp(e, R, x) for x in (0.05, 0.1, 0.2)}
    # secant modulus at half the peak deviator (from q at the start of the axial loading)
    half = q[0] + 0.5 * (q[k] - q[0])
    e50 = None
    for j in range(1, k + 1):
        if q[j] >= half:
            e50 = e[j - 1] + (e[j] - e[j - 1]) * (half - q[j - 1]) / (q[j] - q[j - 1])
            break
    out["e50_mpa"] = (half - q[0]) / e50 / 1e3 if e50 else None

    # dilatancy: sin(psi) = -d / (2 - d), d = d(eps_v)/d(eps_a) over a +-1 % axial window
    def psi_at(j):
        lo = interp(e, curves["volumetric_strain"], max(0.0, e[j] - 0.01))
        hi = interp(e, curves["volumetric_strain"], min(e[-1], e[j] + 0.01))
        de = min(e[-1], e[j] + 0.01) - max(0.0, e[j] - 0.01)
        if lo is None or hi is None or de <= 0:
            return None
        d = (hi - lo) / de
        return math.degrees(math.asin(max(-1.0, min(1.0, -d / (2 - d)))))
    psis = [psi_at(j) for j in range(len(e))]
    psis_ok = [p for p in psis if p is not None]
    out["dilatancy_deg"] = {"at_peak": psis[k], "max": max(psis_ok) if psis_ok else None,
                            "definition": "sin psi = -(d eps_v/d eps_a) / (2 - d eps_v/d eps_a), "
                                          "compression positive, slope over +-1 % axial strain"}
    out["servo_error_max"] = max(curves["servo_error"][1:])
    out["servo_error_mean"] = sum(curves["servo_error"][1:]) / (len(e) - 1)
    out["inertial_number_max"] = max(v for v in curves["inertial_number"] if v is not None)
    out["stability_max"] = max(curves["stability"][1:])
    return out


def snapshot(status):
    result["status"] = status
    result["curves"] = curves
    result.update(summary())
    result["axial"] = {"steps": O.iter - iter0, "sim_time_s": O.time - time0,
                       "wall_clock_s": time.time() - t_a, "cpu_s": time.process_time() - cpu_a,
                       "L0": list(L0), "V0": V0}
    result.update({"steps": O.iter, "dt": O.dt, "wall_clock_s": time.time() - T0,
                   "cpu_s": time.process_time() - CPU0, "spheres": N})


triax.max_vel = MAX_VEL_AXIAL
triax.stressMask = 3
triax.goal1 = triax.goal2 = -SIGMA3
triax.goal3 = -A.strain_rate  # YADE: tension positive; the z walls close at 0.5 * rate * depth
sample()
steps_total = A.axial_strain / (A.strain_rate * O.dt)
every = max(1, int(math.ceil(steps_total / max(1, A.samples - 3))))
say("axial loading: about %d steps, a sample every %d" % (steps_total, every))
while curves["axial_strain"][-1] < A.axial_strain - 1e-12 and len(curves["iter"]) < A.samples:
    left = (A.axial_strain - curves["axial_strain"][-1]) / (A.strain_rate * O.dt)
    O.run(max(1, min(every, int(math.ceil(left)))), True)
    r = sample()
    n = len(curves["iter"])
    if n % 10 == 0 or r["axial_strain"] >= A.axial_strain - 1e-12:
        say("e_a %.4f  e_v %+.4f  s1 %.2f  s3 %.2f (servo %.4f)  R %.3f  Z %.2f  n %.4f  S_c %.2g"
            % (r["axial_strain"], r["volumetric_strain"], r["sigma1_kpa"], r["sigma3_kpa"],
               r["servo_error"], r["stress_ratio"], r["coordination"], r["porosity"],
               r["stability"]))
    if n % 25 == 0:
        snapshot("running")
        write_json(A.out + ".partial", result)

result["end_state"] = stresses_at_equilibrium("end of axial loading")
snapshot("done")
write_json(A.out, result)
if os.path.exists(A.out + ".partial"):
    os.remove(A.out + ".partial")
pk = result["peak"]
say("done: peak sigma1/sigma3 %.3f at e_a %.4f (phi %.2f deg), end ratio %.3f, e_v at end %+.4f, "
    "%d steps, dt %.4g, %.1f s wall, %.1f s CPU -> %s" % (
        pk["stress_ratio"], pk["axial_strain"], pk["phi_deg"], result["end"]["stress_ratio"],
        result["end"]["volumetric_strain"], O.iter, O.dt, result["wall_clock_s"],
        result["cpu_s"], A.out))

# YADE makes /tmp/yade-XXXXXX at start-up and leaves it behind after -x: remove ours
d = os.path.dirname(O.tmpFilename())
if os.path.basename(d).startswith("yade-"):
    shutil.rmtree(d, ignore_errors=True)
