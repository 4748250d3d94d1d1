"""The exports of a 3D Fourier-Voronoi specimen loaded by the real programs (core/export's fv3d
formats: lammps, liggghts, yade, vtk, stl): LAMMPS, LIGGGHTS and YADE each hold one rigid body a
grain, of the grain's clump of spheres, with the grain's own mass (density x the volume of its
surface mesh: in all rho sum V), centre of mass and inertia tensor -- not the spheres' sums --
and VTK's readers give the grains' surfaces back, enclosing their volumes.

The files and the specimen's own values come from the core's test program (test_export_fv3d
--write DIR: a 30-grain specimen of mesh level 2 with clumps, density 2650.5, its five files and
fv3d.json); its path is GP_FV3D_WRITER (tests/CMakeLists.txt sets it), else the build tree's
tests/test_export_fv3d beside the daemon given as argv[1]. The daemon itself is not started: the
files are core/export's, which the daemon streams as they are. Both ctest runs (it_ and it_pg_)
run the same checks.

The programs come from Debian packages (bash deploy/install-deps.sh --test): lammps (lmp),
liggghts, yade, python3-vtk9 (VTK's Python module for /usr/bin/python3, or GPD_VTK_PYTHON). A
missing program is a failure that names the package, never a skip.
"""
import json
import math
import os
import re
import sys
import tarfile
import tempfile
import atexit
import shutil

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
VTK_PYTHON = os.environ.get("GPD_VTK_PYTHON", "/usr/bin/python3")
NGRAINS = 30

# tolerances: masses and centres pass through %.17g text and the programs' own sums; inertia
# through their eigen-decompositions (principal moments and a rotation), so relative to the
# tensor's largest element
MASS_REL = 1e-12
POS_ABS = 1e-12
INERTIA_REL = 1e-9


# ------------------------------------------------------------------ the shared fixture

def writer_path():
    p = os.environ.get("GP_FV3D_WRITER")
    if p:
        return p
    build = os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[1])))
    return os.path.join(build, "tests", "test_export_fv3d")


class Fixture:
    """The specimen's files and values, written once."""

    def __init__(self):
        self.dir = tempfile.mkdtemp(prefix="gpd-fv3d-")
        atexit.register(shutil.rmtree, self.dir, True)
        w = writer_path()
        if not os.access(w, os.X_OK):
            raise AssertionError("the writer %s is missing: build the tests (test_export_fv3d)" % w)
        gpd.run_program([w, "--write", self.dir, str(NGRAINS)], self.dir,
                        "test_export_fv3d --write")
        with open(os.path.join(self.dir, "fv3d.json")) as f:
            self.spec = json.load(f)
        self.grains = self.spec["grains"]
        assert len(self.grains) == NGRAINS, len(self.grains)
        self.rho = self.spec["density"]
        self.total_mass = math.fsum(g["mass"] for g in self.grains)
        assert rel(self.total_mass, self.rho * self.spec["volume"]) < 1e-14

    def path(self, name):
        return os.path.join(self.dir, name)


_FIXTURE = None


def fixture():
    global _FIXTURE
    if _FIXTURE is None:
        _FIXTURE = Fixture()
    return _FIXTURE


def shared(test):
    def run(env):
        return test(fixture())
    run.__name__ = test.__name__
    return run


# ------------------------------------------------------------------ arithmetic

def rel(a, b):
    return abs(a - b) / abs(b)


def quat_matrix(w, x, y, z):
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def from_axes(moments, axes):
    """sum_k moments[k] axes[k] axes[k]^T (axes: unit vectors in the world)"""
    return [[math.fsum(moments[k] * axes[k][i] * axes[k][j] for k in range(3)) for j in range(3)]
            for i in range(3)]


def from_quat(moments, q):
    """R diag(moments) R^T, R the rotation of q = (w, x, y, z): the body axes are R's columns"""
    R = quat_matrix(*q)
    return from_axes(moments, [[R[i][k] for i in range(3)] for k in range(3)])


def tensor_gap(got, want):
    """the largest element of got - want, relative to want's largest"""
    scale = max(abs(v) for row in want for v in row)
    return max(abs(got[i][j] - want[i][j]) for i in range(3) for j in range(3)) / scale


def check_bodies(fx, what, bodies):
    """bodies: {grain id: (mass, centre or None, tensor)} -> the worst gaps, checked"""
    assert sorted(bodies) == list(range(NGRAINS)), (what, sorted(bodies))
    wm = wp = wi = 0.0
    for g in fx.grains:
        mass, centre, tensor = bodies[g["id"]]
        wm = max(wm, rel(mass, g["mass"]))
        if centre is not None:
            wp = max(wp, max(abs(a - b) for a, b in zip(centre, g["centroid"])))
        wi = max(wi, tensor_gap(tensor, g["inertia"]))
    total = math.fsum(b[0] for b in bodies.values())
    print("    %s: %d bodies, total mass %.17g (rho sum V %.17g), worst mass %.1e, centre %.1e m, "
          "inertia %.1e" % (what, len(bodies), total, fx.rho * fx.spec["volume"], wm, wp, wi),
          flush=True)
    assert wm <= MASS_REL, "%s: a body's mass is off by %.3g relative" % (what, wm)
    assert wp <= POS_ABS, "%s: a body's centre of mass is off by %.3g m" % (what, wp)
    assert wi <= INERTIA_REL, "%s: a body's inertia tensor is off by %.3g relative" % (what, wi)
    assert rel(total, fx.rho * fx.spec["volume"]) <= MASS_REL, (what, total)


def thermo(out, what):
    lines = out.splitlines()
    for i, line in enumerate(lines):
        cols = line.split()
        if cols and cols[0] == "Step" and i + 1 < len(lines):
            return {c: float(v) for c, v in zip(cols, lines[i + 1].split())}
    raise AssertionError("%s printed no thermo line:\n%s" % (what, out[-3000:]))


def dump_local(path):
    """the entries of a LAMMPS/LIGGGHTS local dump: (column names, rows of floats)"""
    with open(path) as f:
        lines = f.read().splitlines()
    for i, line in enumerate(lines):
        if line.startswith("ITEM: ENTRIES"):
            return line.split()[2:], [[float(v) for v in ln.split()] for ln in lines[i + 1:] if ln]
    raise AssertionError("%s has no entries" % path)


# ------------------------------------------------------------------ LAMMPS

@shared
def test_lammps(fx):
    """LAMMPS reads the tar's files with its own grains.in: 30 rigid bodies of the spheres, total
    body mass rho sum V; and per body (compute rigid/local) the grain's mass, centre of mass and
    inertia tensor (principal moments and quaternion turned back to a tensor)."""
    gpd.need("lmp", "lammps")
    with tarfile.open(fx.path("fv3d-lammps.tar")) as t:
        names = t.getnames()
        assert names == ["lammps-grains", "lammps-grains/grains.in", "lammps-grains/grains.rigid",
                         "lammps-grains/grains.data"], names
        t.extractall(fx.dir)
    d = fx.path("lammps-grains")
    out = gpd.run_program(["lmp", "-in", "grains.in", "-log", "none"], d, "LAMMPS grains.in")
    rb = re.search(r"^\s*(\d+) rigid bodies with (\d+) atoms", out, re.M)
    assert rb, out[-3000:]
    assert (int(rb.group(1)), int(rb.group(2))) == (NGRAINS, fx.spec["spheres"]), rb.group(0)
    t = thermo(out, "LAMMPS")
    assert int(t["Atoms"]) == fx.spec["spheres"], t
    assert rel(t["c_bodymass"], fx.rho * fx.spec["volume"]) <= MASS_REL, t
    # every body, as LAMMPS holds it
    cols = " ".join("c_bodies[%d]" % k for k in range(1, 14))
    with open(os.path.join(d, "bodies.in"), "w") as f:
        f.write("include grains.in\n"
                "dump bodies all local 1 bodies.dump %s\n"
                "dump_modify bodies format float %%.17g\n"
                "run 0\n" % cols)
    gpd.run_program(["lmp", "-in", "bodies.in", "-log", "none"], d, "LAMMPS bodies")
    _, rows = dump_local(os.path.join(d, "bodies.dump"))
    bodies = {}
    for r in rows:
        # id (its owning atom) mol (= grain id + 1) mass x y z inertiax inertiay inertiaz
        # quatw quati quatj quatk
        bodies[int(r[1]) - 1] = (r[2], r[3:6], from_quat(r[6:9], r[9:13]))
    assert len(rows) == NGRAINS, len(rows)
    check_bodies(fx, "LAMMPS", bodies)


# ------------------------------------------------------------------ LIGGGHTS

@shared
def test_liggghts(fx):
    """LIGGGHTS 3.8 reads the templates; one body of each, inserted with "orientation template"
    in a cell of its own: 30 multisphere bodies, each of its template's grain's mass and inertia
    tensor (principal moments and axes turned back to a tensor), total mass rho sum V."""
    gpd.need("liggghts", "liggghts")
    with open(fx.path("fv3d-liggghts.in")) as f:
        text = f.read()
    ids = re.findall(r"^fix gpt(\d+) all particletemplate/multisphere ", text, re.M)
    assert [int(k) for k in ids] == list(range(1, NGRAINS + 1)), ids
    # a grid of cells, one a template: side 2.5 the largest grain
    side = 2.5 * fx.spec["max_extent"]
    per = int(math.ceil(NGRAINS ** (1 / 3)))
    L = per * side
    lines = ["units si", "atom_style sphere", "atom_modify map array sort 0 0", "boundary f f f",
             "newton off", "communicate single vel yes",
             "region box block 0 %.17g 0 %.17g 0 %.17g units box" % (L, L, L),
             "create_box 1 box", "neighbor %.17g bin" % (0.05 * side), "neigh_modify delay 0",
             "fix m1 all property/global youngsModulus peratomtype 1e7",
             "fix m2 all property/global poissonsRatio peratomtype 0.3",
             "fix m3 all property/global coefficientRestitution peratomtypepair 1 0.5",
             "fix m4 all property/global coefficientFriction peratomtypepair 1 0.5",
             "pair_style gran model hertz tangential history", "pair_coeff * *",
             "timestep 1e-7", "fix ms all multisphere",
             "include %s" % fx.path("fv3d-liggghts.in")]
    for k in range(1, NGRAINS + 1):
        i, j, m = (k - 1) % per, (k - 1) // per % per, (k - 1) // (per * per)
        lines += ["fix d%d all particledistribution/discrete 15485867 1 gpt%d 1.0" % (k, k),
                  "region r%d block %.17g %.17g %.17g %.17g %.17g %.17g units box"
                  % (k, i * side, (i + 1) * side, j * side, (j + 1) * side, m * side,
                     (m + 1) * side),
                  "fix i%d all insert/pack seed 32452843 distributiontemplate d%d insert_every once "
                  "overlapcheck yes all_in yes orientation template particles_in_region 1 region r%d"
                  % (k, k, k)]
    lines += ["fix integr all nve/sphere",
              "compute ct all multisphere property clumptype",
              "compute cm all multisphere property masstotal",
              "compute cx all multisphere property xcm",
              "compute ci all multisphere property inertia",
              "compute ce all multisphere property ex_space",
              "compute cf all multisphere property ey_space",
              "compute cg all multisphere property ez_space",
              "compute mtot all reduce sum c_cm",
              "thermo_style custom step atoms c_mtot", "thermo_modify format float %.17g",
              "run 1",
              "dump bodies all local 1 bodies.dump c_ct c_cm c_ci[1] c_ci[2] c_ci[3] c_ce[1] "
              "c_ce[2] c_ce[3] c_cf[1] c_cf[2] c_cf[3] c_cg[1] c_cg[2] c_cg[3]",
              "dump_modify bodies format \"%s\"" % " ".join(["%.17g"] * 14),
              "run 0"]
    d = os.path.join(fx.dir, "liggghts")
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "in.bodies"), "w") as f:
        f.write("\n".join(lines) + "\n")
    out = gpd.run_program(["liggghts", "-in", "in.bodies", "-log", "none"], d, "LIGGGHTS")
    inserted = re.findall(r"inserted (\d+) particle templates", out)
    assert sum(int(n) for n in inserted) == NGRAINS, inserted
    _, rows = dump_local(os.path.join(d, "bodies.dump"))
    assert len(rows) == NGRAINS, len(rows)
    bodies = {}
    for r in rows:
        axes = [r[5:8], r[8:11], r[11:14]]
        bodies[int(r[0]) - 1] = (r[1], None, from_axes(r[2:5], axes))
    check_bodies(fx, "LIGGGHTS", bodies)


# ------------------------------------------------------------------ YADE

YADE_SCRIPT = r'''
import json, os, shutil, sys
from yade import ymport
from yade.wrapper import FrictMat, ForceResetter, NewtonIntegrator, Sphere

def run():
    path, out_path = sys.argv[1], sys.argv[2]
    O.reset()
    mat = O.materials.append(FrictMat(density=%(rho).17g))
    clumps = ymport.textClumps(path, material=mat)
    summed = [O.bodies[c].state.mass for c, _ in clumps]
    exec("".join(l[4:] for l in open(path) if l.startswith("#py ")), globals())
    ids = grainpack_exact(path, clumps)
    before = {b.id: tuple(b.state.pos) for b in O.bodies if isinstance(b.shape, Sphere)}
    # the members stay where they are as the clumps move (their frames agree)
    O.engines = [ForceResetter(), NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 1e-6
    O.run(3, True)
    moved = max(max(abs(a - b) for a, b in zip(O.bodies[i].state.pos, p)) for i, p in before.items())
    rows = []
    for k, c in enumerate(ids):
        s = O.bodies[c].state
        R = s.ori.toRotationMatrix()
        rows.append({"grain": k, "mass": s.mass, "pos": list(s.pos), "inertia": list(s.inertia),
                     "axes": [[R[i, j] for i in range(3)] for j in range(3)]})
    bodies = [b for b in O.bodies]
    json.dump({"bodies": len(bodies), "slots": len(O.bodies),
               "clumps": sum(1 for b in bodies if b.isClump),
               "spheres": sum(1 for b in bodies if isinstance(b.shape, Sphere)),
               "members": [len(m) for _, m in clumps], "summed": summed, "moved": moved,
               "rows": rows}, open(out_path, "w"))

try:
    run()
finally:
    d = os.path.dirname(O.tmpFilename())
    if os.path.basename(d).startswith("yade-"):
        shutil.rmtree(d, ignore_errors=True)
'''


@shared
def test_yade(fx):
    """YADE: ymport.textClumps makes one clump a grain (its spheres as members); the file's own
    grainpack_exact gives each clump its grain's mass, centroid and inertia tensor (principal
    moments and orientation turned back to a tensor); the members stay in place as the clumps
    move."""
    gpd.need("yade", "yade")
    script = fx.path("yade_check.py")
    with open(script, "w") as f:
        f.write(YADE_SCRIPT % {"rho": fx.rho})
    out_json = fx.path("yade.json")
    gpd.run_program(["yade", "-n", "-x", script, fx.path("fv3d-yade.txt"), out_json], fx.dir,
                    "YADE")
    with open(out_json) as f:
        rep = json.load(f)
    assert rep["clumps"] == NGRAINS and rep["spheres"] == fx.spec["spheres"], rep["clumps"]
    assert rep["bodies"] == NGRAINS + fx.spec["spheres"], rep["bodies"]
    assert rep["slots"] == rep["bodies"] + 1, rep["slots"]  # the carrier's vacant id
    assert rep["members"] == [g["nspheres"] for g in fx.grains], rep["members"]
    assert rep["moved"] <= 1e-12, rep["moved"]
    bodies = {}
    for r in rep["rows"]:
        bodies[r["grain"]] = (r["mass"], r["pos"], from_axes(r["inertia"], r["axes"]))
    check_bodies(fx, "YADE", bodies)
    summed = math.fsum(rep["summed"])
    print("    YADE: textClumps alone weighed the clumps %.6g kg (their spheres, overlaps twice), "
          "%.3g x the grains'" % (summed, summed / fx.total_mass), flush=True)


# ------------------------------------------------------------------ VTK

STL_SCRIPT = r'''
import json, sys
import vtk
r = vtk.vtkSTLReader()
r.SetFileName(sys.argv[1])
r.ScalarTagsOn()
r.MergingOff()
r.Update()
p = r.GetOutput()
tags = p.GetCellData().GetScalars()
m = vtk.vtkMassProperties()
m.SetInputData(p)
m.Update()
json.dump({"cells": p.GetNumberOfCells(), "points": p.GetNumberOfPoints(),
           "solids": len(set(tags.GetValue(i) for i in range(tags.GetNumberOfTuples()))),
           "volume": m.GetVolume()}, open(sys.argv[2], "w"))
'''


def need_vtk():
    if not (os.path.isfile(VTK_PYTHON) and os.access(VTK_PYTHON, os.X_OK)):
        raise AssertionError("%s is missing: install the Debian packages python3 and python3-vtk9"
                             % VTK_PYTHON)


def tri_volume(a, b, c, o):
    p = [a[k] - o[k] for k in range(3)]
    q = [b[k] - o[k] for k in range(3)]
    r = [c[k] - o[k] for k in range(3)]
    return (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0])
            + p[2] * (q[0] * r[1] - q[1] * r[0])) / 6.0


@shared
def test_vtk(fx):
    """VTK's vtkPolyDataReader opens the vtk file: every grain's vertices and triangles, the
    triangles of a grain enclosing its volume to 1e-9, cell data grain_id, cell_id, volume;
    vtkSTLReader opens the stl file: one solid a grain, its facets, the enclosed volume (VTK keeps
    STL points in 32-bit floats: to 1e-5)."""
    need_vtk()
    out_json = fx.path("vtk.json")
    gpd.run_program([VTK_PYTHON, os.path.join(HERE, "export_check_vtk.py"), out_json,
                     fx.path("fv3d.vtk")], fx.dir, "VTK reader")
    with open(out_json) as f:
        r = json.load(f)[0]
    assert r["errors"] == [], r["errors"]
    nd, nt = fx.spec["directions"], fx.spec["triangles"]
    pts, polys = r["points"], r["polys"]
    assert len(pts) == NGRAINS * nd and len(polys) == NGRAINS * nt == r["cells"], (len(pts), len(polys))
    vol = [0.0] * NGRAINS
    for k, poly in enumerate(polys):
        g = k // nt
        assert len(poly) == 3 and all(g * nd <= i < (g + 1) * nd for i in poly), (k, poly)
        vol[g] += tri_volume(pts[poly[0]], pts[poly[1]], pts[poly[2]], pts[g * nd])
    worst = max(rel(v, g["volume"]) for v, g in zip(vol, fx.grains))
    total = math.fsum(vol)
    print("    VTK: %d points, %d triangles, enclosed volume %.17g (grains %.17g), worst grain %.1e"
          % (len(pts), len(polys), total, fx.spec["volume"], worst), flush=True)
    assert worst <= 1e-9 and rel(total, fx.spec["volume"]) <= 1e-9, (worst, total)
    cd = r["cell_data"]
    assert sorted(cd) == ["cell_id", "grain_id", "volume"], sorted(cd)
    assert cd["grain_id"]["values"] == [k // nt for k in range(NGRAINS * nt)]
    assert cd["cell_id"]["values"] == [fx.grains[k // nt]["cell"] for k in range(NGRAINS * nt)]
    assert cd["volume"]["values"] == [fx.grains[k // nt]["volume"] for k in range(NGRAINS * nt)]
    assert r["field_data"]["box_lo"]["values"] == fx.spec["box_lo"], r["field_data"]
    assert r["field_data"]["box_hi"]["values"] == fx.spec["box_hi"], r["field_data"]
    # STL
    script = fx.path("stl_check.py")
    with open(script, "w") as f:
        f.write(STL_SCRIPT)
    gpd.run_program([VTK_PYTHON, script, fx.path("fv3d.stl"), fx.path("stl.json")], fx.dir,
                    "VTK STL reader")
    with open(fx.path("stl.json")) as f:
        s = json.load(f)
    print("    STL: %d solids, %d facets, enclosed volume %.9g (grains %.9g)"
          % (s["solids"], s["cells"], s["volume"], fx.spec["volume"]), flush=True)
    assert s["solids"] == NGRAINS and s["cells"] == NGRAINS * nt, s
    assert rel(s["volume"], fx.spec["volume"]) <= 1e-5, s


if __name__ == "__main__":
    if len(sys.argv) >= 2 and not os.path.isabs(sys.argv[1]):
        sys.argv[1] = os.path.abspath(sys.argv[1])
    gpd.main([test_lammps, test_liggghts, test_yade, test_vtk])
