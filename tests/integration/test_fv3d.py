"""The fourier-voronoi-3d kind through the daemon: the contract's example scaled down (60 grains
on a level-2 mesh) to done, its result against the contract and against what the test
recomputes itself from the returned geometry: each grain's volume from its radii, the shared
icosphere, its rotation and scale (the divergence theorem over the mesh's triangles); every
grain vertex and every clump sphere inside its cell, whose faces' planes the test makes from the
cells' vertices (counter-clockwise from outside); the cells' volumes and their sum against the
container; neighbours mutual, walls on the container; the solid fraction, the descriptor means
and the clump counts against the stats. A cylinder, a polyhedron and a sieve law; the same
specimen bit for bit on 1 and 2 threads; the refusals at submit (422 at the field's JSON
pointer, too_large for the work, the memory and the result); the views; the exports (the VTK
surfaces enclose the grains' volumes, the LAMMPS bodies weigh rho V, 409 without clumps or
grains); cancel while running."""
import hashlib
import io
import json
import math
import os
import sys
import tarfile
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

KIND = "fourier-voronoi-3d"

# the contract's example, scaled down: 60 grains on a 162-direction mesh
EXAMPLE = {
    "kind": KIND, "seed": 42,
    "container": {"box": [1, 1, 1]},
    "particles": 60,
    "size": {"law": "lognormal", "cov": 0.5, "of": "cells"},
    "orientation": {"axis": [0, 0, 1], "anisotropy": 1.0},
    "shape": {"D2": 0.1, "D3": 0.05, "D8": 0.02, "alpha": -2, "beta": -2, "elongation": 0.8,
              "flatness": 0.8},
    "solid_fraction": 0.55,
    "clump": {"spheres_max": 30, "min_radius_ratio": 0.1},
    "mesh_level": 2,
    "outputs": ["grains", "clumps", "descriptors", "cells"],
}
VIEWS = ["section", "projection", "size", "descriptors"]
STATS_KEYS = {"particles", "imc_error", "imc_steps", "solid_fraction", "container_volume",
              "grains_short", "fit", "descriptors", "shape", "mesh", "clumps"}
DESC3 = ["elongation", "flatness", "sphericity", "convexity"]
DESC2 = ["elongation", "roundness", "circularity", "regularity"]
AXES = ["long", "intermediate", "short"]


def close(a, b, rel=1e-9, abs_=1e-12):
    return abs(a - b) <= max(rel * max(abs(a), abs(b)), abs_)


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def rotation(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def grain_vertices(g, dirs):
    """vertex i = center + scale R(rotation) radii[i] directions[i]"""
    R, s, c = rotation(g["rotation"]), g["scale"], g["center"]
    out = []
    for r, d in zip(g["radii"], dirs):
        p = [r * d[0], r * d[1], r * d[2]]
        out.append([c[k] + s * dot(R[k], p) for k in range(3)])
    return out


def mesh_volume(verts, tris, origin):
    """the volume a closed counter-clockwise mesh bounds (tetrahedra from origin)"""
    v = 0.0
    for a, b, c in tris:
        pa, pb, pc = sub(verts[a], origin), sub(verts[b], origin), sub(verts[c], origin)
        v += dot(pa, cross(pb, pc))
    return v / 6


def cell_planes(cell):
    """each face's outward plane (n, d) from its vertices, n by Newell's method"""
    vs, planes = cell["vertices"], []
    for f in cell["faces"]:
        n = [0.0, 0.0, 0.0]
        for k in range(len(f)):
            p, q = vs[f[k]], vs[f[(k + 1) % len(f)]]
            n[0] += (p[1] - q[1]) * (p[2] + q[2])
            n[1] += (p[2] - q[2]) * (p[0] + q[0])
            n[2] += (p[0] - q[0]) * (p[1] + q[1])
        m = math.sqrt(dot(n, n))
        n = [x / m for x in n]
        d = sum(dot(n, vs[i]) for i in f) / len(f)
        planes.append((n, d))
    return planes


def cell_volume(cell):
    """the divergence theorem over the faces, fanned from their first vertex"""
    vs, o, v = cell["vertices"], cell["vertices"][0], 0.0
    for f in cell["faces"]:
        for k in range(1, len(f) - 1):
            v += dot(sub(vs[f[0]], o), cross(sub(vs[f[k]], o), sub(vs[f[k + 1]], o)))
    return v / 6


def mean_sd(vals):
    m = sum(vals) / len(vals)
    return m, math.sqrt(sum((v - m) ** 2 for v in vals) / (len(vals) - 1))


def run(d, spec, timeout=120):
    jid = d.submit(spec)
    job = d.wait(jid, timeout=timeout * gpd.TIME_SCALE)
    assert job["status"] == "succeeded", job
    gpd.check_job_object(job)
    st, _, r = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200, (st, r)
    return jid, job, r


def check_cells(r, volume, on_wall):
    """the cells: volumes, containment of seeds, faces outward, neighbours mutual, walls on the
    container; their volumes sum to the container's"""
    cells = r["cells"]
    assert [c["id"] for c in cells] == list(range(len(cells)))
    total = 0.0
    for c in cells:
        assert set(c) == {"id", "seed", "vertices", "faces", "neighbours", "volume"}, set(c)
        assert len(c["faces"]) == len(c["neighbours"]) >= 4, c["id"]
        v = cell_volume(c)
        assert close(v, c["volume"], 1e-9), (c["id"], v, c["volume"])
        total += v
        planes = cell_planes(c)
        size = v ** (1 / 3)
        for n, dd in planes:  # the seed is inside: every face is outward
            assert dot(n, c["seed"]) <= dd + 1e-9 * size, c["id"]
        for f, j in zip(c["faces"], c["neighbours"]):
            if j >= 0:
                assert c["id"] in cells[j]["neighbours"], (c["id"], j)
            else:
                assert all(on_wall(c["vertices"][i]) for i in f), (c["id"], f)
    assert close(total, volume, 1e-9), (total, volume)
    return {c["id"]: cell_planes(c) for c in cells}


def check_grains(r, planes):
    """each grain: its volume from its mesh, every vertex inside its cell"""
    ico = r["icosphere"]
    dirs, tris = ico["directions"], ico["triangles"]
    level = r["stats"]["mesh"]["level"]
    assert len(dirs) == 10 * 4 ** level + 2 and len(tris) == 20 * 4 ** level, (len(dirs), level)
    for d in dirs:
        assert close(dot(d, d), 1.0, 1e-12), d
    total = 0.0
    for g in r["grains"]:
        assert g["cell"] == g["id"], g["id"]
        assert close(sum(x * x for x in g["rotation"]), 1.0, 1e-12), g["rotation"]
        assert g["scale"] > 0 and len(g["radii"]) == len(dirs) and min(g["radii"]) > 0
        verts = grain_vertices(g, dirs)
        v = mesh_volume(verts, tris, g["center"])
        assert close(v, g["volume"], 1e-9), (g["id"], v, g["volume"])
        total += v
        cell = r["cells"][g["cell"]]
        size = cell["volume"] ** (1 / 3)
        worst = max(dot(n, p) - d for n, d in planes[g["cell"]] for p in verts)
        assert worst <= 1e-9 * size, (g["id"], worst)
    return total


def check_clumps(r, planes):
    n = 0
    for c in r["clumps"]:
        assert set(c) == {"grain", "spheres", "volume_error", "inertia_error"}, set(c)
        assert 1 <= len(c["spheres"]) <= r["stats"]["clumps"]["spheres_max"]
        rmax = max(s[3] for s in c["spheres"])
        for x, y, z, rad in c["spheres"]:
            assert 0 < rad <= rmax
            assert rad >= r["stats"]["clumps"]["min_radius_ratio"] * rmax * (1 - 1e-9)
            for nn, d in planes[c["grain"]]:
                assert dot(nn, [x, y, z]) + rad <= d + 1e-9, (c["grain"], x, y, z, rad)
        n += len(c["spheres"])
        assert -1 < c["volume_error"] <= 1e-3, c
    cl = r["stats"]["clumps"]
    assert cl["spheres"]["total"] == n and cl["spheres"]["max"] <= cl["spheres_max"], cl


def check_stats(r, spec, grain_total, volume):
    st = r["stats"]
    assert set(st) >= STATS_KEYS, sorted(st)
    n = len(r["grains"])
    assert st["particles"] == {"target": spec.get("particles", n), "achieved": n}, st["particles"]
    sf = st["solid_fraction"]
    assert sf["target"] == spec["solid_fraction"]
    assert close(sf["achieved"], grain_total / volume, 1e-9), (sf, grain_total / volume)
    assert close(st["container_volume"], volume, 1e-12)
    ie = st["imc_error"]
    assert ie["measure"] == "AD" and ie["target"] == 0.05 and ie["stop_reason"] in (
        "threshold", "max_steps", "stalled"), ie
    assert st["imc_steps"]["max"] == 1000000 and st["imc_steps"]["achieved"] > 0
    fit = st["fit"]
    for k in ("cell_volume", "grain_volume"):
        b = fit[k]
        assert set(b) >= {"law", "target", "achieved", "ks", "ks_critical", "w1", "n", "cdf"}, b
        assert b["n"] == n and close(b["ks_critical"], 1.36 / math.sqrt(n), 1e-12), b
        assert set(b["target"]) == {"mean", "cov"} and set(b["achieved"]) == {"mean", "cov"}
    assert close(fit["cell_volume"]["target"]["mean"], volume / n, 1e-12)
    assert close(fit["cell_volume"]["achieved"]["mean"], volume / n, 1e-9)
    cells = [c["volume"] for c in r["cells"]]
    assert close(fit["cell_volume"]["achieved"]["cov"], mean_sd(cells)[1] / mean_sd(cells)[0], 1e-9)
    assert close(fit["grain_volume"]["achieved"]["mean"], grain_total / n, 1e-9)
    for k in ("cell_orientation", "grain_orientation"):
        o = fit[k]
        assert set(o) == {"target", "ks", "ks_critical", "n"}, o
        assert o["target"]["anisotropy"] == spec["orientation"]["anisotropy"], o
        assert close(dot(o["target"]["axis"], o["target"]["axis"]), 1, 1e-12), o
    # the descriptors' means against the grains'
    ds = st["descriptors"]
    for name in DESC3:
        m, sd = mean_sd([g["descriptors"][name] for g in r["grains"]])
        assert close(ds[name]["mean"], m, 1e-9) and close(ds[name]["sd"], sd, 1e-9), (name, ds)
        assert len(ds[name]["edges"]) == len(ds[name]["achieved"]) + 1
        assert close(sum(ds[name]["achieved"]), 1, 1e-9)
    assert ds["elongation"]["target"] == spec["shape"]["elongation"]
    assert ds["flatness"]["target"] == spec["shape"]["flatness"]
    assert ds["sphericity"]["target"] is None
    for a in AXES:
        for q in DESC2:
            m, _ = mean_sd([g["descriptors"]["projections"][a][q] for g in r["grains"]])
            assert close(ds["projections"][a][q]["mean"], m, 1e-9), (a, q)
    sh = st["shape"]
    assert sh["form"] == "D" and sh["degree"] == 30 and len(sh["spectrum"]) == 31, sh
    assert sh["spectrum"][0] == 1 and close(sh["spectrum"][2], spec["shape"]["D2"], 1e-15)
    assert sh["star_certain"] is (sh["star_bound"] < 1)
    # the warnings say what was not reached
    short = st["grains_short"]["count"]
    assert short == sum(1 for g in r["grains"] if g["volume"] < (1 - 1e-9) * spec[
        "solid_fraction"] * r["cells"][g["cell"]]["volume"]), short
    if short:
        assert any(("%d of %d grains could not reach" % (short, n)) in w for w in r["warnings"])


def check_result(r, spec):
    assert r["kind"] == KIND and r["seed"] == spec["seed"]
    assert r["outputs"] == spec["outputs"] and r["container"] == spec["container"]
    assert set(r) == {"kind", "seed", "outputs", "container", "stats", "warnings", "timings",
                      "icosphere", "grains", "cells", "clumps"}, sorted(r)
    assert set(r["timings"]) == {"imc", "grains", "stats", "total"}, r["timings"]
    assert all(isinstance(w, str) for w in r["warnings"])
    for g in r["grains"]:
        assert set(g) == {"id", "cell", "center", "rotation", "scale", "radii", "volume",
                          "descriptors"}, set(g)
        assert set(g["descriptors"]) == set(DESC3) | {"projections"}
        assert set(g["descriptors"]["projections"]) == set(AXES)


def check_views(d, jid):
    for view in VIEWS:
        st, h, body = d.request("GET", "/v1/jobs/%s/svg?view=%s" % (jid, view))
        assert st == 200, (view, st, body[:300])
        assert h["Content-Type"].startswith("image/svg+xml"), h["Content-Type"]
        root = ET.fromstring(body)
        assert root.tag in ("{http://www.w3.org/2000/svg}svg", "svg"), (view, root.tag)
    st, _, body = d.request("GET", "/v1/jobs/%s/svg?view=section&z=0.25" % jid)
    assert st == 200 and b"z = 0.25 m" in body, body[:300]
    st, _, j = d.json("GET", "/v1/jobs/%s/svg?view=section&z=2" % jid)
    assert st == 400 and "valid z from 0 to 1" in j["error"]["message"], j
    st, _, j = d.json("GET", "/v1/jobs/%s/svg?view=psd" % jid)
    assert st == 400 and all(v in j["error"]["message"] for v in VIEWS), j
    st, _, j = d.json("GET", "/v1/jobs/%s/export?format=csv" % jid)
    gpd.check_error_body(st, j, "invalid_parameter")
    assert st == 400 and all(f in j["error"]["message"] for f in EXPORTS), j


# the exports of this kind (core/export's fv3d pack; tests/integration/test_export_fv3d.py
# loads the same files into LAMMPS, LIGGGHTS and YADE)
EXPORTS = ("lammps", "liggghts", "yade", "vtk", "stl")
DENSITY = 2650.0


def check_exports(d, jid, r):
    """the downloads against the result: the VTK and STL surfaces enclose each grain's volume,
    the LAMMPS bodies weigh rho V each"""
    vols = [g["volume"] for g in r["grains"]]
    ntri = len(r["icosphere"]["triangles"])
    st, h, body = d.request("GET", "/v1/jobs/%s/export?format=vtk" % jid)
    assert st == 200, (st, body[:300])
    pts, polys = vtk_surfaces(body.decode())
    assert len(polys) == len(vols) * ntri, (len(polys), len(vols), ntri)
    enclosed = mesh_volume(pts, polys, pts[0])
    assert close(enclosed, math.fsum(vols), 1e-9), (enclosed, math.fsum(vols))
    st, h, body = d.request("GET", "/v1/jobs/%s/export?format=stl" % jid)
    assert st == 200 and body.decode().count("facet normal") == len(vols) * ntri, st
    st, h, body = d.request("GET", "/v1/jobs/%s/export?format=lammps" % jid)
    assert st == 200 and h["Content-Type"].startswith("application/x-tar"), (st, h)
    with tarfile.open(fileobj=io.BytesIO(body)) as tar:
        names = tar.getnames()
        rigid = tar.extractfile("lammps-grains/grains.rigid").read().decode()
    assert {"lammps-grains/grains.data", "lammps-grains/grains.in",
            "lammps-grains/grains.rigid"} <= set(names), names
    bodies = [ln.split() for ln in rigid.splitlines() if ln.strip() and ln.split()[0].isdigit()
              and len(ln.split()) >= 11]
    masses = sorted(float(b[1]) for b in bodies)
    assert len(masses) == len(vols), (len(masses), len(vols))
    assert all(close(m, DENSITY * v, 1e-12) for m, v in zip(masses, sorted(vols)))
    for fmt in ("liggghts", "yade"):
        st, _, body = d.request("GET", "/v1/jobs/%s/export?format=%s" % (jid, fmt))
        assert st == 200 and len(body) > 1000, (fmt, st)


def vtk_surfaces(text):
    """the points and the triangles of a legacy ASCII polydata"""
    tok = text.split()
    i = tok.index("POINTS")
    n = int(tok[i + 1])
    vals = [float(t) for t in tok[i + 3:i + 3 + 3 * n]]
    pts = [vals[3 * k:3 * k + 3] for k in range(n)]
    j = tok.index("POLYGONS")
    m = int(tok[j + 1])
    polys, k = [], j + 3
    for _ in range(m):
        c = int(tok[k])
        polys.append([int(t) for t in tok[k + 1:k + 1 + c]])
        k += 1 + c
    return pts, polys


def test_example(env):
    d = env.daemon(workers=1)
    jid, job, r = run(d, EXAMPLE)
    check_result(r, EXAMPLE)
    planes = check_cells(r, 1.0, lambda p: min(min(p), 1 - max(p)) <= 1e-12)
    total = check_grains(r, planes)
    check_clumps(r, planes)
    check_stats(r, EXAMPLE, total, 1.0)
    # the brief, the done detail and the summary
    b = job["brief"]
    assert b["particles"] == 60 and b["headline"]["name"] == "solid_fraction", b
    assert close(b["headline"]["achieved"], r["stats"]["solid_fraction"]["achieved"], 1e-12)
    det = job["progress"]["detail"]
    assert det["warnings"] == r["warnings"] and det["steps"] == r["stats"]["imc_steps"]["achieved"]
    assert set(det["fit"]) == set(r["stats"]["fit"]) and "cdf" not in det["fit"]["cell_volume"]
    st, _, s = d.json("GET", "/v1/jobs/%s/summary" % jid)
    assert st == 200 and s == {k: v for k, v in r.items()
                               if k not in ("grains", "cells", "clumps", "icosphere")}, sorted(s)
    check_views(d, jid)
    check_exports(d, jid, r)
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def test_containers_and_sieve(env):
    """a cylinder (the 64-facet prism), a polyhedron (a tetrahedron) and a sieve law"""
    d = env.daemon(workers=2)
    base = {"kind": KIND, "seed": 3, "mesh_level": 1, "outputs": ["grains", "cells"],
            "particles": 30}
    r0, h0 = 0.5, 1.0
    cyl = dict(base, container={"cylinder": {"radius": r0, "height": h0}})
    tet = dict(base, container={"polyhedron": {"halfspaces": [[1, 1, 1, 1], [-1, 0, 0, 0],
                                                               [0, -1, 0, 0], [0, 0, -1, 0]]}})
    sieve = dict(base, container={"box": [0.1, 0.1, 0.1]},
                 size={"law": "sieve", "sieve": [[15, 0], [20, 40], [30, 100]]})
    del sieve["particles"]
    cells_only = dict(base, outputs=["cells"])
    ids = [d.submit(s) for s in (cyl, tet, sieve, cells_only)]
    res = []
    for jid in ids:
        job = d.wait(jid, timeout=120 * gpd.TIME_SCALE)
        assert job["status"] == "succeeded", job
        res.append(d.json("GET", "/v1/jobs/%s/result" % jid)[2])
    # the cylinder: the prism's volume; walls on its facets, bottom or top
    prism = 32 * r0 * r0 * math.sin(2 * math.pi / 64) * h0
    apothem = r0 * math.cos(math.pi / 64)
    def on_prism(p):
        ang = math.atan2(p[1], p[0])
        k = math.floor(ang / (2 * math.pi / 64))
        t = 2 * math.pi * (k + 0.5) / 64
        return (abs(p[2]) <= 1e-12 or abs(p[2] - h0) <= 1e-12 or
                abs(p[0] * math.cos(t) + p[1] * math.sin(t) - apothem) <= 1e-12)
    r = res[0]
    assert close(r["stats"]["container_volume"], prism, 1e-12), r["stats"]["container_volume"]
    assert close(r["stats"]["lost_volume"], math.pi * r0 * r0 * h0 - prism, 1e-9)
    planes = check_cells(r, prism, on_prism)
    check_grains(r, planes)
    # the tetrahedron
    r = res[1]
    planes = check_cells(r, 1 / 6, lambda p: min(p) <= 1e-12 or abs(sum(p) - 1) <= 1e-12)
    check_grains(r, planes)
    # the sieve: the count from the container, solid_fraction and the law's mean volume
    r = res[2]
    n = len(r["grains"])
    assert r["stats"]["particles"]["achieved"] == n == r["stats"]["particles"]["target"] > 10
    planes = check_cells(r, 1e-3, lambda p: min(min(p), 0.1 - max(p)) <= 1e-12)
    total = check_grains(r, planes)
    assert close(r["stats"]["solid_fraction"]["achieved"], total / 1e-3, 1e-9)
    p = r["stats"]["fit"]["passing"]
    assert all(close(a, b, 1e-12) for a, b in zip(p["diameters"], [0.015, 0.02, 0.03])), p
    assert p["target"] == [0, 40, 100] and len(p["achieved"]) == 3, p
    assert r["stats"]["fit"]["grain_volume"]["law"] == "sieve"
    st, _, spec = d.json("GET", "/v1/jobs/%s/spec" % ids[2])
    assert "particles" not in spec and spec["size"]["of"] == "grains", spec
    # cells only: no grains, clumps nor icosphere in the result; the views that need them 409
    r = res[3]
    assert set(r) == {"kind", "seed", "outputs", "container", "stats", "warnings", "timings",
                      "cells"}, sorted(r)
    check_cells(r, 1.0, lambda p: min(min(p), 1 - max(p)) <= 1e-12)
    for view, want in (("section", 200), ("projection", 409), ("size", 200),
                       ("descriptors", 409)):
        st, _, body = d.request("GET", "/v1/jobs/%s/svg?view=%s" % (ids[3], view))
        assert st == want, (view, st, body[:200])
    # no clumps asked: the surfaces export, the rigid bodies 409; no grains asked: no pack
    st, _, body = d.request("GET", "/v1/jobs/%s/export?format=vtk" % ids[0])
    assert st == 200, (st, body[:200])
    for jid, fmt in ((ids[0], "lammps"), (ids[0], "yade"), (ids[3], "vtk")):
        st, _, j = d.json("GET", "/v1/jobs/%s/export?format=%s" % (jid, fmt))
        gpd.check_error_body(st, j, "missing_output")
        assert st == 409, (fmt, st, j)
    for jid in ids[:3]:  # the views of each container (the outline of a cylinder, a polyhedron)
        for view in ("section", "projection"):
            st, _, body = d.request("GET", "/v1/jobs/%s/svg?view=%s" % (jid, view))
            assert st == 200 and ET.fromstring(body) is not None, (view, st, body[:200])
        st, _, j = d.json("GET", "/v1/jobs/%s/svg?view=descriptors" % jid)
        assert st == 409 and "descriptors" in j["error"]["message"], (st, j)
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def test_threads_bit_for_bit(env):
    """the same spec on 1 and on 2 threads: the same result bytes"""
    spec = dict(EXAMPLE, seed=5, particles=24, mesh_level=1)
    digests = []
    for threads, db in ((1, env.db), (2, os.path.join(env.dir, "other.db"))):
        d = env.daemon(workers=1, db=db, extra=["--job-threads", str(threads)])
        jid = d.submit(spec)
        assert d.wait(jid, timeout=120 * gpd.TIME_SCALE)["status"] == "succeeded"
        st, _, r = d.json("GET", "/v1/jobs/%s/result" % jid)
        assert st == 200
        del r["timings"]  # seconds: the only member that may differ
        digests.append(hashlib.sha256(json.dumps(r, sort_keys=True).encode()).hexdigest())
    assert digests[0] == digests[1], digests


def test_refused_at_submit(env):
    d = env.daemon(workers=1)
    ex = dict(EXAMPLE)
    box = {"box": [1, 1, 1]}
    slab = [[1, 0, 0, 1], [-1, 0, 0, 0], [0, 1, 0, 1], [0, -1, 0, 0]]
    cases = [
        (dict(ex, particles="many"), "/particles", "expected an integer"),
        (dict(ex, container={"box": [1, 1]}), "/container/box", None),
        (dict(ex, container={"box": [1, 1, 1], "cylinder": {"radius": 1, "height": 1}}),
         "/container/cylinder", "cannot be combined"),
        (dict(ex, container={"cylinder": {"radius": 0, "height": 1}}),
         "/container/cylinder/radius", None),
        (dict(ex, container={"polyhedron": {"halfspaces": slab}}),
         "/container/polyhedron/halfspaces", "bounded"),
        (dict(ex, container={"polyhedron": {"halfspaces": slab + [[0, 0, 1, 1], [0, 0, 0, 1]]}}),
         "/container/polyhedron/halfspaces/5", "zero"),
        (dict(ex, container={"polyhedron": {"halfspaces": slab + [[0, 0, 1, 1], [0, 0, -1, -2]]}}),
         "/container/polyhedron/halfspaces", None),
        (dict(ex, size={"law": "normal", "cov": 0.7}), "/size/cov", "at most 0.6"),
        (dict(ex, size={"law": "sieve", "sieve": [[1, 0], [2, 100]]}), "/particles", "sieve"),
        (dict({k: v for k, v in ex.items() if k != "particles"},
              size={"law": "sieve", "sieve": [[2, 0], [1, 100]]}), "/size/sieve/1/0", "increase"),
        (dict(ex, size={"sieve": [[1, 0], [2, 100]]}), "/size/sieve", "only allowed"),
        (dict(ex, orientation={"axis": [0, 0, 0]}), "/orientation/axis", "zero"),
        (dict(ex, orientation={"anisotropy": 0}), "/orientation/anisotropy", None),
        (dict(ex, shape={"D2": 0.1, "spectrum": [1, 0, 0.1]}), "/shape/spectrum",
         "cannot be combined"),
        (dict(ex, shape={"spectrum": [1] + [0.01] * 31}), "/shape/spectrum", "at most 31"),
        (dict(ex, shape={"D2": 0.9, "D3": 0.6, "D8": 0.3}), "/shape/D8", "star-shaped"),
        (dict(ex, shape={"elongation": 0}), "/shape/elongation", None),
        (dict(ex, solid_fraction=1), "/solid_fraction", None),
        (dict(ex, clump={"spheres_max": 0}), "/clump/spheres_max", None),
        (dict(ex, outputs=["odec"]), "/outputs/0", None),
        (dict(ex, mesh_level=7), "/mesh_level", None),
        (dict(ex, imc={"error": "E1"}), "/imc/error", "unknown field"),
        (dict(ex, colour=1), "/colour", "unknown field"),
    ]
    for spec, pointer, needle in cases:
        gpd.refused(d, spec, pointer, needle)
    # too large: the work, a sieve's count, the memory
    gpd.refused(d, dict(ex, imc={"max_steps": 1000000000}), "/imc/max_steps", "budget",
                code="too_large")
    gpd.refused(d, dict({k: v for k, v in ex.items() if k != "particles"},
                        size={"law": "sieve", "sieve": [[1, 0], [2, 100]]}), "/size/sieve",
                "over the limit", code="too_large")
    gpd.refused(d, dict(ex, mesh_level=6, particles=200000, outputs=["cells"]), "/mesh_level",
                "GB", code="too_large")
    # the result bound of a daemon with a small --max-result-mb
    d2 = env.daemon(workers=1, db=os.path.join(env.dir, "small.db"),
                    extra=["--max-result-mb", "1"])
    gpd.refused(d2, dict(ex, particles=2000), "/particles", "--max-result-mb", code="too_large")
    assert box == {"box": [1, 1, 1]}


def test_cancel_while_running(env):
    d = env.daemon(workers=1)
    spec = dict(EXAMPLE, seed=1, particles=20000, mesh_level=4)
    jid = d.submit(spec)
    deadline = time.time() + 60 * gpd.TIME_SCALE
    seen = set()
    while time.time() < deadline:
        j = d.job(jid)
        p = j["progress"]
        seen.add(p["phase"])
        if p["phase"] == "imc" and p["detail"]:
            assert set(p["detail"]) == {"steps", "error"}, p
            break
        time.sleep(0.05)
    assert "imc" in seen, seen
    t0 = time.time()
    st, _, j = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    assert j["error"]["code"] == "cancelled", j
    j = d.wait(jid, timeout=30 * gpd.TIME_SCALE)
    assert j["status"] == "cancelled", j
    assert time.time() - t0 < 10 * gpd.TIME_SCALE
    st, _, j = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 409, (st, j)


if __name__ == "__main__":
    gpd.main([test_example, test_containers_and_sieve, test_threads_bit_for_bit,
              test_refused_at_submit, test_cancel_while_running])
