"""GET /v1/jobs/{id}/export (issue #8): every format is loaded into the real program that reads it
-- LAMMPS, LIGGGHTS, YADE, VTK's own reader -- and compared with the job's JSON result; csv parses
back to the result's floats exactly; headers; the error answers; a job without odec has a view
pack that draws its pictures as the export pack does and exports nothing.

The programs come from Debian packages (bash deploy/install-deps.sh): lammps (lmp), liggghts,
yade, python3-vtk9 (VTK's Python module, for /usr/bin/python3 -- set GPD_VTK_PYTHON to use
another interpreter). A missing program is a failure that names the package, never a skip.

One daemon and one set of jobs serve every check below (the jobs are built once, the exports
downloaded once); YADE and VTK are started once for all the files.
"""
import atexit
import csv
import json
import math
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
VTK_PYTHON = os.environ.get("GPD_VTK_PYTHON", "/usr/bin/python3")

FORMATS_3D = ["lammps", "liggghts", "yade", "vtk", "csv"]
FORMATS_2D = ["lammps", "yade", "vtk", "csv"]
EXT = {"lammps": "data", "liggghts": "data", "yade": "txt", "vtk": "vtk", "csv": "csv"}
MIME = {"lammps": "text/plain", "liggghts": "text/plain", "yade": "text/plain",
        "vtk": "application/octet-stream", "csv": "text/csv"}

RHO_3D = 2650.5       # a non-default material density (the default is 2600): must be used
RHO_2D = 2650.0       # the documented 2D density (no material in a 2D spec)

# A small 3D packing (~55 spheres of 1-2 mm in a 6 mm box, ~1 s). Whether the DEM reaches the
# porosity in so small a box depends on the seed and the density, so a few seeds are tried.
SPEC_3D = {
    "kind": "spheres-3d",
    "box": [0.006, 0.006, 0.006],
    "sieve": [[1, 0], [2, 100]],
    "sieve_units": "mm",
    "porosity": 0.5,
    "material": {"density": RHO_3D},
    "outputs": ["spheres"],
}
SEEDS_3D = (3, 7, 11, 1, 2, 5, 13)
# Its tiled twin: 216 copies, ~12,000 spheres, so that its pack (32 bytes a sphere) and its
# result are over the 256 KiB that the daemon serves from memory: they are streamed from SQLite.
TILING = [6, 6, 6]
STREAM_SMALL = 256 * 1024

# 2D: the standard small job (grains, odec, descriptors, cells; square container) and one in a
# circle away from the origin without descriptors (VTK then has 3 cell arrays, not 7).
SPEC_2D = gpd.SMALL_2D
SPEC_2D_CIRCLE = {
    "kind": "fourier-voronoi-2d",
    "seed": 5,
    "particles": 20,
    "container": {"circle": {"center": [2.0, -1.0], "radius": 0.5}},
    "imc": {"error": "E3", "threshold": 0.05, "max_steps": 20000, "init": "halton"},
    "contour_points": 32,
    "outputs": ["grains", "odec"],
}
SPEC_2D_NO_ODEC = dict(SPEC_2D, particles=20, outputs=["grains", "descriptors"])
SPEC_3D_NO_SPHERES = dict(SPEC_3D, outputs=["fabric"])
DESCRIPTORS = ["elongation", "roundness", "circularity", "regularity"]


# ------------------------------------------------------------------ the shared fixture

class Fixture:
    """The daemon, the finished jobs, their results and every export, downloaded once."""

    def __init__(self):
        self.env = gpd.Env(sys.argv[1])
        atexit.register(self.env.close)
        self.dir = os.path.join(self.env.dir, "files")
        os.makedirs(self.dir)
        self.d = self.env.daemon(workers=2)
        d = self.d
        t0 = time.time()
        ids2 = {"sq": d.submit(SPEC_2D), "circle": d.submit(SPEC_2D_CIRCLE),
                "no_odec": d.submit(SPEC_2D_NO_ODEC)}
        self.j3, self.jt, self.seed3 = self._submit_3d()
        self.j2, self.jc, self.j2_no_odec = ids2["sq"], ids2["circle"], ids2["no_odec"]
        for jid in ids2.values():
            job = d.wait(jid, timeout=120 * gpd.TIME_SCALE)
            assert job["status"] == "succeeded", job
        self.results = {}
        for jid in (self.j3, self.jt, self.j2, self.jc):
            st, h, body = d.request("GET", "/v1/jobs/%s/result" % jid, timeout=60)
            assert st == 200, (st, body[:300])
            self.results[jid] = json.loads(body)
        # every export, with its headers
        self.files, self.headers = {}, {}
        for jid, fmts in ((self.j3, FORMATS_3D), (self.jt, FORMATS_3D), (self.j2, FORMATS_2D),
                          (self.jc, FORMATS_2D)):
            for f in fmts:
                st, h, body = d.request("GET", "/v1/jobs/%s/export?format=%s" % (jid, f),
                                        timeout=60)
                assert st == 200, (jid, f, st, body[:300])
                path = os.path.join(self.dir, "%s-%s.%s" % (jid, f, EXT[f]))
                with open(path, "wb") as out:
                    out.write(body)
                self.files[jid, f] = path
                self.headers[jid, f] = h
        print("    fixture: 3D seed %d (%d spheres, tiled %d), 2D %d and %d grains; %.1fs"
              % (self.seed3, len(self.results[self.j3]["spheres"]),
                 len(self.results[self.jt]["spheres"]), len(self.results[self.j2]["grains"]),
                 len(self.results[self.jc]["grains"]), time.time() - t0), flush=True)

    def _submit_3d(self):
        """The small 3D job and its tiled twin, at the first seed whose packing succeeds."""
        tried = []
        for seed in SEEDS_3D:
            a = self.d.submit(dict(SPEC_3D, seed=seed))
            b = self.d.submit(dict(SPEC_3D, seed=seed, tiling=TILING))
            ja = self.d.wait(a, timeout=300 * gpd.TIME_SCALE)
            jb = self.d.wait(b, timeout=300 * gpd.TIME_SCALE)
            if ja["status"] == "succeeded":
                assert jb["status"] == "succeeded", ("the tiled job failed", jb)
                return a, b, seed
            tried.append((seed, ja["error"]))
        raise AssertionError("no small 3D packing succeeded at seeds %s: %s" % (SEEDS_3D, tried))

    def spheres(self, jid):
        return self.results[jid]["spheres"]

    def grains(self, jid):
        return self.results[jid]["grains"]


_FIXTURE = None
_FIXTURE_ERROR = None


def fixture():
    global _FIXTURE, _FIXTURE_ERROR
    if _FIXTURE_ERROR:
        raise AssertionError("the shared fixture failed to build (see the first failure)")
    if _FIXTURE is None:
        try:
            _FIXTURE = Fixture()
        except Exception:
            _FIXTURE_ERROR = True
            raise
    return _FIXTURE


def shared(test):
    """Runs a check against the shared fixture; on failure prints the shared daemon's log."""
    def run(env):
        try:
            return test(fixture())
        except Exception:
            if _FIXTURE is not None:
                print("---- shared daemon log ----\n" + _FIXTURE.d.read_log())
            raise
    run.__name__ = test.__name__
    return run


# ------------------------------------------------------------------ programs

def need_vtk():
    if not (os.path.isfile(VTK_PYTHON) and os.access(VTK_PYTHON, os.X_OK)):
        raise AssertionError("%s is missing: VTK's reader runs under the system Python; install "
                             "the Debian packages python3 and python3-vtk9" % VTK_PYTHON)
    p = subprocess.run([VTK_PYTHON, "-c", "import vtk"], capture_output=True, text=True,
                       timeout=120)
    if p.returncode != 0:
        raise AssertionError("`import vtk` fails under %s: install the Debian package "
                             "python3-vtk9 (bash deploy/install-deps.sh)\n%s"
                             % (VTK_PYTHON, p.stderr[-2000:]))


def thermo(out, what):
    """The first thermo line after a 'Step ...' header, as {column: float}."""
    lines = out.splitlines()
    for i, line in enumerate(lines):
        cols = line.split()
        if cols and cols[0] == "Step" and i + 1 < len(lines):
            vals = lines[i + 1].split()
            assert len(vals) == len(cols), (what, line, lines[i + 1])
            return {c: float(v) for c, v in zip(cols, vals)}
    raise AssertionError("%s printed no thermo line:\n%s" % (what, out[-3000:]))


def sphere_mass(spheres, rho):
    return math.fsum(rho * (4.0 / 3.0) * math.pi * s[3] ** 3 for s in spheres)


def rel(a, b):
    return abs(a - b) / abs(b)


def run_lammps_3d(fx, binary, jid, fmt, what):
    data = fx.files[jid, fmt]
    sort = " sort 0 0" if binary == "liggghts" else ""  # LIGGGHTS: bin size 0 without a pair style
    script = ("units si\natom_style sphere\natom_modify map array%s\nboundary f f f\n"
              "read_data %s\nvariable m equal mass(all)\nthermo_style custom step atoms v_m\n"
              "thermo_modify format float %%.17g\nrun 0\n" % (sort, os.path.basename(data)))
    inp = data + ".in"
    with open(inp, "w") as f:
        f.write(script)
    out = gpd.run_program([binary, "-in", os.path.basename(inp), "-log", "none"], fx.dir, what)
    t = thermo(out, what)
    n = len(fx.spheres(jid))
    assert int(t["Atoms"]) == n, "%s: %s atoms after read_data/run 0, the result has %d" % (
        what, t["Atoms"], n)
    mcol = "v_m" if "v_m" in t else "m"
    want = sphere_mass(fx.spheres(jid), RHO_3D)
    assert rel(t[mcol], want) <= 1e-9, "%s: total mass %r, want sum rho 4/3 pi r^3 = %r" % (
        what, t[mcol], want)
    return t


def data_header_box(path):
    box = {}
    with open(path) as f:
        for line in f:
            m = re.match(r"^(\S+) (\S+) ([xyz])lo \3hi$", line.strip())
            if m:
                box[m.group(3)] = (float(m.group(1)), float(m.group(2)))
            if line.startswith("Atoms"):
                break
    return box


# ------------------------------------------------------------------ checks

@shared
def test_headers(fx):
    """Content-Type per format, Content-Disposition: attachment; filename="<job>-<format>.<ext>",
    HEAD like GET, and a second download gives the same bytes."""
    for (jid, f), h in sorted(fx.headers.items()):
        ct = h["Content-Type"] or ""
        assert ct.split(";")[0].strip() == MIME[f], (jid, f, ct)
        if ct.startswith("text/"):
            assert "charset=utf-8" in ct, (f, ct)
        want = 'attachment; filename="%s-%s.%s"' % (jid, f, EXT[f])
        assert h["Content-Disposition"] == want, (h["Content-Disposition"], want)
        assert os.path.getsize(fx.files[jid, f]) > 0
    for jid, f in ((fx.j3, "lammps"), (fx.j2, "vtk")):
        st, h, body = fx.d.request("HEAD", "/v1/jobs/%s/export?format=%s" % (jid, f))
        assert st == 200 and body == b"", (st, body[:100])
        assert h["Content-Disposition"] == fx.headers[jid, f]["Content-Disposition"], h
        st, h, body = fx.d.request("GET", "/v1/jobs/%s/export?format=%s" % (jid, f))
        with open(fx.files[jid, f], "rb") as fh:
            assert st == 200 and body == fh.read(), "a second download differs (%s)" % f


@shared
def test_csv_round_trip(fx):
    """csv parses back to the result's geometry, float for float."""
    for jid in (fx.j3, fx.jt):
        with open(fx.files[jid, "csv"], newline="") as f:
            rows = list(csv.reader(f))
        assert rows[0] == ["x", "y", "z", "r"], rows[0]
        got = [[float(v) for v in row] for row in rows[1:]]
        want = fx.spheres(jid)
        assert len(got) == len(want), (len(got), len(want))
        for i, (a, b) in enumerate(zip(got, want)):
            assert a == b, "3D csv row %d: %r != result %r" % (i + 1, a, b)
    for jid in (fx.j2, fx.jc):
        with open(fx.files[jid, "csv"], newline="") as f:
            rows = list(csv.reader(f))
        assert rows[0] == ["grain", "x", "y", "r"], rows[0]
        want = [[g["id"]] + d for g in fx.grains(jid) for d in g["discs"]]
        got = [[int(row[0])] + [float(v) for v in row[1:]] for row in rows[1:]]
        assert len(got) == len(want), (len(got), len(want))
        for i, (a, b) in enumerate(zip(got, want)):
            assert a == b, "2D csv row %d: %r != result %r" % (i + 1, a, b)


@shared
def test_lammps_3d(fx):
    """LAMMPS reads the 3D data file (plain and tiled): run 0 reports the result's atom count
    and a total mass of sum rho 4/3 pi r^3 (rho = the spec's 2650.5) to 1e-9 relative; the
    box is the job's box."""
    gpd.need("lmp", "lammps")
    for jid in (fx.j3, fx.jt):
        run_lammps_3d(fx, "lmp", jid, "lammps", "LAMMPS 3D %s" % jid[:8])
        box = data_header_box(fx.files[jid, "lammps"])
        want = fx.results[jid]["box"]
        assert box == {"x": (0.0, want[0]), "y": (0.0, want[1]), "z": (0.0, want[2])}, (box, want)


@shared
def test_liggghts_3d(fx):
    """LIGGGHTS 3.8 reads the 3D liggghts file: same atom count and mass."""
    gpd.need("liggghts", "liggghts")
    for jid in (fx.j3, fx.jt):
        run_lammps_3d(fx, "liggghts", jid, "liggghts", "LIGGGHTS 3D %s" % jid[:8])


@shared
def test_lammps_2d(fx):
    """LAMMPS reads the 2D data file with the input lines its header documents: as many rigid
    bodies as grains, as many atoms as discs, and the grains' total mass = 2650 * sum(area)."""
    gpd.need("lmp", "lammps")
    for jid in (fx.j2, fx.jc):
        data = fx.files[jid, "lammps"]
        with open(data) as f:
            head = f.read(4096)
        m = re.search(r"^#\s+comm_modify vel yes cutoff (\S+)$", head, re.M)
        assert m, "the 2D LAMMPS header does not document the comm_modify cutoff:\n" + head
        script = ("dimension 2\nunits si\natom_style hybrid sphere molecular\nread_data %s\n"
                  "pair_style gran/hooke/history 1e5 NULL 0 NULL 0.5 0\npair_coeff * *\n"
                  "neigh_modify exclude molecule/intra all\ncomm_modify vel yes cutoff %s\n"
                  "fix grains all rigid/small molecule\nfix plane all enforce2d\n"
                  "variable m equal mass(all)\nthermo_style custom step atoms v_m\n"
                  "thermo_modify format float %%.17g\nrun 0\n" % (os.path.basename(data), m.group(1)))
        with open(data + ".in", "w") as f:
            f.write(script)
        what = "LAMMPS 2D %s" % jid[:8]
        out = gpd.run_program(["lmp", "-in", os.path.basename(data) + ".in", "-log", "none"],
                              fx.dir, what)
        grains = fx.grains(jid)
        ndiscs = sum(len(g["discs"]) for g in grains)
        rb = re.search(r"^\s*(\d+) rigid bodies with (\d+) atoms", out, re.M)
        assert rb, "%s: no 'N rigid bodies with M atoms' line:\n%s" % (what, out[-3000:])
        assert (int(rb.group(1)), int(rb.group(2))) == (len(grains), ndiscs), (
            what, rb.group(0), len(grains), ndiscs)
        t = thermo(out, what)
        assert int(t["Atoms"]) == ndiscs, (what, t, ndiscs)
        want = RHO_2D * math.fsum(g["area"] for g in grains)
        assert rel(t["v_m"], want) <= 1e-9, "%s: total mass %r, want 2650 * sum(area) = %r" % (
            what, t["v_m"], want)


@shared
def test_yade(fx):
    """YADE imports the yade files (ymport.text in 3D, ymport.textClumps in 2D): as many
    spheres as the result (3D) and one clump per grain made of its discs (2D), at the result's
    positions and radii exactly. One YADE run for all the files."""
    gpd.need("yade", "yade")
    script = os.path.join(HERE, "export_check_yade.py")
    out_json = os.path.join(fx.dir, "yade.json")
    args = ["3d:" + fx.files[fx.j3, "yade"], "3d:" + fx.files[fx.jt, "yade"],
            "2d:" + fx.files[fx.j2, "yade"], "2d:" + fx.files[fx.jc, "yade"]]
    out = gpd.run_program(["yade", "-n", "-x", script, out_json] + args, fx.dir, "YADE")
    assert os.path.exists(out_json), "YADE wrote no report:\n" + out[-4000:]
    with open(out_json) as f:
        rep = json.load(f)
    assert len(rep) == 4, rep
    for r, jid in zip(rep[:2], (fx.j3, fx.jt)):
        want = fx.spheres(jid)
        assert r["bodies"] == len(want) == len(r["spheres"]), (r["bodies"], len(want))
        for i, (a, b) in enumerate(zip(r["spheres"], want)):
            assert a == b, "YADE 3D sphere %d: %r != result %r" % (i, a, b)
    for r, jid in zip(rep[2:], (fx.j2, fx.jc)):
        grains = fx.grains(jid)
        ndiscs = sum(len(g["discs"]) for g in grains)
        assert r["clumps"] == len(grains) == len(r["members"]), (r["clumps"], len(grains))
        assert r["spheres"] == ndiscs and r["bodies"] == ndiscs + len(grains), (r, ndiscs)
        for g, members in zip(grains, r["members"]):
            assert len(members) == len(g["discs"]), (g["id"], len(members), len(g["discs"]))
            for a, dsk in zip(members, g["discs"]):
                assert a == [dsk[0], dsk[1], 0.0, dsk[2]], (g["id"], a, dsk)


def run_vtk(fx, paths):
    need_vtk()
    out_json = os.path.join(fx.dir, "vtk.json")
    gpd.run_program([VTK_PYTHON, os.path.join(HERE, "export_check_vtk.py"), out_json] + paths,
                    fx.dir, "VTK reader")
    with open(out_json) as f:
        return json.load(f)


@shared
def test_vtk(fx):
    """VTK's vtkPolyDataReader opens the vtk files: 3D one vertex per sphere at its centre,
    radius array and box field data; 2D one polygon per grain (its contour), one vertex per
    disc, radius 0 on contours and r on disc centres, per-grain cell arrays. Float for float."""
    jobs = [fx.j3, fx.jt, fx.j2, fx.jc]
    rep = run_vtk(fx, [fx.files[j, "vtk"] for j in jobs])
    for r in rep:
        assert r["errors"] == [], r["errors"]
    for r, jid in zip(rep[:2], jobs[:2]):
        sp = fx.spheres(jid)
        n = len(sp)
        assert len(r["points"]) == n and r["cells"] == n and len(r["verts"]) == n, (
            len(r["points"]), r["cells"], n)
        assert r["polys"] == [] and r["lines"] == 0 and r["strips"] == 0
        assert r["verts"] == [[i] for i in range(n)]
        assert r["points"] == [s[:3] for s in sp], "3D points differ from the result's centres"
        rad = r["point_data"]["radius"]
        assert rad["components"] == 1 and rad["values"] == [s[3] for s in sp], "radius differs"
        box = fx.results[jid]["box"]
        assert r["field_data"]["box_lo"]["values"] == [0.0, 0.0, 0.0], r["field_data"]
        assert r["field_data"]["box_hi"]["values"] == box, (r["field_data"], box)
    for r, jid in zip(rep[2:], jobs[2:]):
        grains = fx.grains(jid)
        contour = [p for g in grains for p in g["contour"]]
        discs = [dk for g in grains for dk in g["discs"]]
        ng, nd, npt = len(grains), len(discs), len(contour)
        assert len(r["points"]) == npt + nd, (len(r["points"]), npt, nd)
        assert len(r["polys"]) == ng and len(r["verts"]) == nd and r["cells"] == ng + nd, (
            len(r["polys"]), len(r["verts"]), r["cells"], ng, nd)
        pts = r["points"]
        for g, poly in zip(grains, r["polys"]):
            assert [pts[k] for k in poly] == [[x, y, 0.0] for x, y in g["contour"]], (
                "polygon of grain %d differs from its contour" % g["id"])
        assert [pts[v[0]] for v in r["verts"]] == [[x, y, 0.0] for x, y, _ in discs]
        assert all(len(v) == 1 for v in r["verts"])
        rad = r["point_data"]["radius"]["values"]
        want_rad = [0.0] * npt + [dk[2] for dk in discs]
        assert rad == want_rad, "2D radius array differs"
        # cell data: disc vertices first (each with its grain's values), then the polygons
        cd = r["cell_data"]
        has_desc = "descriptors" in fx.results[jid]["grains"][0]
        names = ["grain_id", "area", "orientation_deg"] + (DESCRIPTORS if has_desc else [])
        assert sorted(cd) == sorted(names), (sorted(cd), names)
        for name in names:
            def val(g):
                if name == "grain_id":
                    return g["id"]
                if name in DESCRIPTORS:
                    return g["descriptors"][name]
                return g[name]
            want = [val(g) for g in grains for _ in g["discs"]] + [val(g) for g in grains]
            assert cd[name]["values"] == want, "cell array %s differs" % name
        assert cd["grain_id"]["type"] in ("int", "long", "long long", "idtype"), cd["grain_id"]


@shared
def test_tiled_export(fx):
    """A tiled job exports the tiled packing: count = the result's spheres = stats.particles
    = 216 x the sample; the box is the tiled box; the pack is large enough to be streamed."""
    rt, r3 = fx.results[fx.jt], fx.results[fx.j3]
    n = len(rt["spheres"])
    copies = TILING[0] * TILING[1] * TILING[2]
    assert n == copies * len(r3["spheres"]), (n, len(r3["spheres"]))
    assert 128 + 32 * n > STREAM_SMALL, "the tiled pack (%d spheres) is served from memory" % n
    assert rt["stats"]["particles"] == n, (rt["stats"]["particles"], n)
    for f in FORMATS_3D:
        with open(fx.files[fx.jt, f]) as fh:
            text = fh.read()
        if f in ("lammps", "liggghts"):
            assert re.search(r"^%d atoms$" % n, text, re.M), f
            assert len(text.split("\nAtoms # sphere\n\n", 1)[1].splitlines()) == n, f
        elif f == "yade":
            assert sum(1 for ln in text.splitlines() if ln and not ln.startswith("#")) == n
        elif f == "csv":
            assert len(text.splitlines()) == n + 1
        else:
            assert re.search(r"^POINTS %d double$" % n, text, re.M), f
    # the sample's box is where its lid ended (within the porosity slack of the spec's box)
    assert [v * t for v, t in zip(r3["box"], TILING)] == rt["box"], (r3["box"], rt["box"])


def expect_error(d, path, status, code, pointer=None):
    st, _, j = d.json("GET", path)
    assert st == status, (path, st, j)
    gpd.check_error_body(st, j, code, pointer)
    return j["error"]


@shared
def test_errors(fx):
    """Unknown/missing/wrong-dimension format -> 400 listing the valid ones; unknown job -> 404;
    a job not succeeded (running, cancelled, failed) -> 409 not_ready; a 2D job without odec /
    a 3D job without spheres -> 409 missing_output at /outputs; methods other than GET/HEAD ->
    405."""
    d = fx.d
    for q in ("format=xyz", "format=LAMMPS", "format=", "", "fmt=csv", "format=csv,vtk"):
        e = expect_error(d, "/v1/jobs/%s/export?%s" % (fx.j3, q), 400, "invalid_parameter")
        for f in FORMATS_3D:
            assert f in e["message"], (q, e)
    for q in ("format=liggghts", "format=nope"):
        e = expect_error(d, "/v1/jobs/%s/export?%s" % (fx.j2, q), 400, "invalid_parameter")
        assert "lammps, yade, vtk, csv" in e["message"] and "liggghts" not in e["message"].split(
            ";")[0], e
    expect_error(d, "/v1/jobs/0123456789abcdef0123456789abcdef/export?format=csv", 404,
                 "not_found")
    expect_error(d, "/v1/jobs/nosuchjob/export?format=csv", 404, "not_found")
    for m in ("POST", "PUT", "DELETE"):
        st, h, j = d.json(m, "/v1/jobs/%s/export?format=csv" % fx.j3)
        assert st == 405 and "GET" in (h["Allow"] or ""), (m, st, j)

    # missing outputs
    no_sph = d.submit(dict(SPEC_3D_NO_SPHERES, seed=fx.seed3))
    for jid, fmts, word in ((fx.j2_no_odec, FORMATS_2D, "odec"), (no_sph, FORMATS_3D, "spheres")):
        job = d.wait(jid, timeout=300 * gpd.TIME_SCALE)
        assert job["status"] == "succeeded", job
        for f in fmts:
            e = expect_error(d, "/v1/jobs/%s/export?format=%s" % (jid, f), 409, "missing_output",
                             "/outputs")
            assert '"%s"' % word in e["message"], e

    # not succeeded: queued or running, then cancelled; and failed
    long_id = d.submit(gpd.LONG_2D)
    st = d.job(long_id)["status"]
    assert st in ("queued", "running"), st
    for f in FORMATS_2D:
        expect_error(d, "/v1/jobs/%s/export?format=%s" % (long_id, f), 409, "not_ready")
    # the format is checked first: a bad one is a 400 even before the job is done
    expect_error(d, "/v1/jobs/%s/export?format=liggghts" % long_id, 400, "invalid_parameter")
    st, _, j = d.json("DELETE", "/v1/jobs/" + long_id)
    assert st == 200, (st, j)
    assert d.wait(long_id)["status"] == "cancelled"
    expect_error(d, "/v1/jobs/%s/export?format=csv" % long_id, 409, "not_ready")
    bad = d.submit(dict(SPEC_3D, seed=1, porosity=0.1))  # far denser than spheres pack: fails
    job = d.wait(bad, timeout=300 * gpd.TIME_SCALE)
    assert job["status"] == "failed", job
    e = expect_error(d, "/v1/jobs/%s/export?format=lammps" % bad, 409, "not_ready")
    assert "failed" in e["message"], e


@shared
def test_view_pack(fx):
    """The standard small job without odec stores a view pack (its grains without discs): its
    five views are byte for byte those of the same job with odec (drawn from its export pack),
    and every export of it is 409 missing_output as for a job without a pack."""
    d = fx.d
    jid = d.submit(dict(SPEC_2D, outputs=["grains", "descriptors", "cells"]))
    job = d.wait(jid, timeout=120 * gpd.TIME_SCALE)
    assert job["status"] == "succeeded", job
    for view in ("packing", "cells", "size", "orientation", "descriptors"):
        got = [d.request("GET", "/v1/jobs/%s/svg?view=%s" % (j, view)) for j in (fx.j2, jid)]
        assert all(st == 200 for st, _, _ in got), (view, [st for st, _, _ in got])
        assert got[0][2] == got[1][2], "%s: the view pack draws another picture" % view
    for f in FORMATS_2D:
        e = expect_error(d, "/v1/jobs/%s/export?format=%s" % (jid, f), 409, "missing_output",
                         "/outputs")
        assert '"odec"' in e["message"], e


@shared
def test_clean_exit(fx):
    """The shared daemon stops cleanly after serving every export (under ASan: no leak)."""
    rc = fx.d.stop()
    assert rc == 0, "daemon exit status %s:\n%s" % (rc, fx.d.read_log())


if __name__ == "__main__":
    if len(sys.argv) >= 2 and not os.path.isabs(sys.argv[1]):
        sys.argv[1] = os.path.abspath(sys.argv[1])
    gpd.main([test_headers, test_csv_round_trip, test_lammps_3d, test_liggghts_3d,
              test_lammps_2d, test_yade, test_vtk, test_tiled_export, test_errors,
              test_view_pack, test_clean_exit])
