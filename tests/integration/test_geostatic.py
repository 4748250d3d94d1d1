"""The geostatic-3d kind: a small flipped specimen (2 x 1 x 2 tiles of 8-12 mm spheres) settled
under gravity through the daemon, with phi' from a triaxial job; the result against the contract
and against what the test recomputes from the returned spheres itself: the weight of the grains
above each slab's mid-plane (sphere caps cut by the plane) against the profile's weight and its
sigma_v (2 %), the bottom wall's force against the whole weight, K0 per slab and its mean, the
porosity; the same packing by job and inline bit for bit; every SVG view; the csv export
against the profile; a packing not at rest within max_steps (a warning, not a failure); the
refusals at submit; cancel while settling."""
import csv
import io
import math
import os
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

KIND = "geostatic-3d"

# the specimen of tests/core/3d/test_geostatic.c: 296 spheres of 8-12 mm flipped 2 x 1 x 2
SPECIMEN = {
    "kind": "spheres-3d",
    "seed": 3,
    "box": [0.06, 0.06, 0.08],
    "sieve": [[8, 0], [12, 100]],
    "sieve_units": "mm",
    "porosity": 0.44,
    "tiling": [2, 1, 2],
    "outputs": ["spheres"],
}
SLAB = 0.02
G = 9.81

PROFILE_KEYS = ["depth", "sigma_xx_kpa", "sigma_yy_kpa", "sigma_zz_kpa", "weight_kpa", "k0",
                "porosity", "coordination", "sigma_xx_full_kpa", "sigma_yy_full_kpa",
                "sigma_zz_full_kpa", "k0_full", "k0_counted", "equilibrium_counted"]
VIEWS = ["profile", "k0", "stress-map"]


def geo(specimen, **kw):
    spec = {"kind": KIND, "seed": 3, "specimen": specimen, "slab": SLAB, "wall_margin_dmax": 1}
    spec.update(kw)
    return spec


def close(a, b, rel=1e-9, abs_=1e-12):
    return abs(a - b) <= max(rel * max(abs(a), abs(b)), abs_)


def cap_volume(z, r, plane):
    """The volume of the sphere (centre height z, radius r) above the plane."""
    if plane <= z - r:
        return 4.0 / 3.0 * math.pi * r ** 3
    if plane >= z + r:
        return 0.0
    h = z + r - plane
    return math.pi * h * h * (3 * r - h) / 3


def weight_kpa(spheres, plane, density, area):
    """The weight of the grains above the plane over the area, kPa, from the spheres alone."""
    return density * G * sum(cap_volume(s[2], s[3], plane) for s in spheres) / area * 1e-3


def job_of(d, spec, timeout=120):
    jid = d.submit(spec)
    job = d.wait(jid, timeout=timeout)
    assert job["status"] == "succeeded", job
    return jid


def check_statics(r):
    """The profile against the weight the test computes from the spheres; the walls."""
    sp, p, st = r["spheres"], r["profile"], r["stats"]
    bx, by, bz = r["box"]
    area, rho = bx * by, r["material"]["density"]
    assert len(sp) == st["particles"] == r["specimen"]["particles"]
    for x, y, z, rad in sp:
        assert -1e-4 < x < bx + 1e-4 and -1e-4 < y < by + 1e-4 and -1e-4 < z, (x, y, z)
    worst = 0.0
    for i, depth in enumerate(p["depth"]):
        w = weight_kpa(sp, bz - depth, rho, area)
        assert close(p["weight_kpa"][i], w, 1e-9, 1e-12), (i, p["weight_kpa"][i], w)
        if p["equilibrium_counted"][i]:
            err = abs(p["sigma_zz_full_kpa"][i] - w) / w
            worst = max(worst, err)
    tol = 0.02 + st["stability"]
    assert 0 < worst <= tol, ("sigma_v against the weight above", worst)
    assert close(st["equilibrium"]["max_error"], worst, 1e-9), (st["equilibrium"], worst)
    # the bottom wall carries the whole weight (frictionless lateral walls, at rest)
    total = rho * G * sum(4.0 / 3.0 * math.pi * s[3] ** 3 for s in sp)
    bottom = st["whole"]["wall_stress_kpa"][4] * 1e3 * area
    assert abs(bottom - total) / total < 2e-3, (bottom, total)
    assert close(st["whole"]["weight_n"], total, 1e-9)
    # the opposite lateral walls push alike; Love-Weber against the walls within 2 %
    ws = st["whole"]["wall_stress_kpa"]
    assert abs(ws[0] - ws[1]) / ws[0] < 5e-3 and abs(ws[2] - ws[3]) / ws[2] < 5e-3, ws
    lw, walls = st["whole"]["love_weber_kpa"], st["whole"]["walls_kpa"]
    for k in range(3):
        assert abs(lw[k][k] - walls[k]) / walls[k] < 0.02, (k, lw[k][k], walls[k])
    # the porosity of the box from the spheres (their overlaps with the walls are ~1e-6)
    solid = total / (rho * G)
    assert abs(st["whole"]["porosity"] - (1 - solid / (bx * by * bz))) < 1e-4, st["whole"]


def check_k0(r, phi_deg):
    p, k0 = r["profile"], r["stats"]["k0"]
    assert close(k0["theory"], 1 - math.sin(math.radians(phi_deg)), 1e-12), (k0, phi_deg)
    counted = []
    for i in range(len(p["depth"])):
        want = (p["sigma_xx_kpa"][i] + p["sigma_yy_kpa"][i]) / 2 / p["sigma_zz_kpa"][i]
        assert close(p["k0"][i], want, 1e-9), (i, p["k0"][i], want)
        if p["k0_counted"][i]:
            counted.append(p["k0"][i])
    assert len(counted) == k0["slabs"] >= 2, (counted, k0)
    mean = sum(counted) / len(counted)
    sd = math.sqrt(sum((v - mean) ** 2 for v in counted) / (len(counted) - 1))
    assert close(k0["mean"], mean, 1e-9) and close(k0["sd"], sd, 1e-9), (k0, mean, sd)
    assert 0.2 < mean < 1.5, k0
    # the slabs next to the top are not counted: the first one never
    assert not p["k0_counted"][0] and not p["equilibrium_counted"][0]


def check_result(r, specimen, specimen_job, triax_job, phi_deg):
    """r against the contract and its own numbers; specimen: the spheres-3d job's summary."""
    assert r["kind"] == KIND and r["seed"] == 3
    assert r["specimen"]["job"] == specimen_job and r["specimen"]["part"] == "tiled"
    assert r["specimen"]["tiling"] == [2, 1, 2] and r["box"] == specimen["box"], r["box"]
    assert r["specimen"]["sample_box"] == specimen["sample_box"]
    assert r["specimen"]["particles"] == specimen["stats"]["particles"]
    assert r["phi_from"] == ({"job": triax_job} if triax_job else None), r["phi_from"]
    assert close(r["phi_deg"], phi_deg, 1e-15), (r["phi_deg"], phi_deg)
    assert r["gravity"] == [0, 0, -9.81] and r["vertical"] == "z"
    st = r["stats"]
    assert st["converged"] is True and st["stability"] <= 1e-4, st
    assert st["stability_contacts"] <= 2e-4, st
    # slabs of about SLAB tiling the height
    assert close(st["slab"] * 8, r["box"][2], 1e-12) and abs(st["slab"] - SLAB) < 0.1 * SLAB, st
    assert close(st["margin"], st["dmax"], 1e-12), st
    assert r["warnings"] == [], r["warnings"]
    p = r["profile"]
    n = len(p["depth"])
    assert n == 8, n
    for k in PROFILE_KEYS:
        assert len(p[k]) == n, k
    for i in range(n):
        assert close(p["depth"][i], st["slab"] * (i + 0.5), 1e-12), p["depth"]
        assert 0.2 < p["porosity"][i] < 1 and p["coordination"][i] >= 0, i
    m = r["map"]
    assert m["horizontal"] == "x" and m["vertical"] == "z", m
    assert m["tile"] == [specimen["sample_box"][0], specimen["sample_box"][2]], m
    assert close(m["nx"] * m["dx"], r["box"][0], 1e-12), m
    assert close(m["nz"] * m["dz"], r["box"][2], 1e-12), m
    assert len(m["sigma_v_kpa"]) == m["nz"] and all(len(row) == m["nx"] for row in m["sigma_v_kpa"])
    check_statics(r)
    check_k0(r, phi_deg)
    assert set(r["timings"]) == {"specimen", "settling", "measure", "total"}, r["timings"]


def check_views(d, jid, missing=()):
    for view in VIEWS:
        st, h, body = d.request("GET", "/v1/jobs/%s/svg?view=%s" % (jid, view))
        if view in missing:
            assert st == 409, (view, st, body[:200])
            continue
        assert st == 200, (view, st, body[:300])
        assert h["Content-Type"].startswith("image/svg+xml"), h["Content-Type"]
        root = ET.fromstring(body)
        assert root.tag in ("{http://www.w3.org/2000/svg}svg", "svg"), (view, root.tag)
    st, _, j = d.json("GET", "/v1/jobs/%s/svg?view=psd" % jid)
    assert st == 400 and all(v in j["error"]["message"] for v in VIEWS), j


def check_csv(d, jid, r):
    st, h, body = d.request("GET", "/v1/jobs/%s/export?format=csv" % jid)
    assert st == 200, (st, body[:300])
    assert h["Content-Type"].startswith("text/csv"), h["Content-Type"]
    rows = list(csv.reader(io.StringIO(body.decode())))
    assert rows[0] == PROFILE_KEYS, rows[0]
    p = r["profile"]
    want = [[float(v) if not isinstance(v, bool) else float(v) for v in
             (p[k][i] for k in PROFILE_KEYS)] for i in range(len(p["depth"]))]
    got = [[float(v) for v in row] for row in rows[1:]]
    assert got == want, "the csv is not the profile"


def test_by_job_and_inline(env):
    d = env.daemon(workers=2)
    sid = job_of(d, SPECIMEN)
    # phi' from a triaxial test of the same sample, at a fast rate
    tid = job_of(d, {"kind": "triaxial-3d", "specimen": {"job": sid}, "confining_kpa": [20, 40],
                     "axial_strain": 0.05, "strain_rate": 1.0, "outputs": ["curves"]})
    _, _, tr = d.json("GET", "/v1/jobs/%s/summary" % tid)
    phi_deg = tr["stats"]["mohr_coulomb"]["phi_deg"]
    gid = d.submit(geo({"job": sid}, phi_from={"job": tid}))
    # while it settles, progress says so with steps and S_c
    seen = set()
    deadline = time.time() + 120 * gpd.TIME_SCALE
    while True:
        job = d.job(gid)
        seen.add(job["progress"]["phase"])
        if job["progress"]["phase"] == "settling":
            det = job["progress"]["detail"]
            assert det["steps"] >= 0 and "stability" in det, det
        if job["status"] in gpd.FINAL:
            break
        assert time.time() < deadline, job
        time.sleep(0.02)
    assert job["status"] == "succeeded", job
    assert "settling" in seen, seen
    gpd.check_brief(job["brief"])
    _, _, r = d.json("GET", "/v1/jobs/%s/result" % gid)
    _, _, sres = d.json("GET", "/v1/jobs/%s/summary" % sid)
    check_result(r, sres, sid, tid, phi_deg)
    assert job["brief"]["headline"]["name"] == "k0"
    assert job["brief"]["headline"]["achieved"] == r["stats"]["k0"]["mean"]
    assert close(job["brief"]["headline"]["target"], r["stats"]["k0"]["theory"], 1e-12)
    check_views(d, gid)
    check_csv(d, gid, r)
    # the effective spec keeps the phi' it read and the specimen's spec
    _, _, spec = d.json("GET", "/v1/jobs/%s/spec" % gid)
    assert spec["phi_from"] == {"job": tid, "phi_deg": phi_deg}, spec["phi_from"]
    assert spec["specimen"]["spec"]["tiling"] == [2, 1, 2]
    # the same packing inline, phi' given: the same spheres and profile, bit for bit
    inline = {k: v for k, v in SPECIMEN.items() if k != "kind"}
    iid = job_of(d, geo({"spec": inline}, phi_deg=phi_deg))
    _, _, ri = d.json("GET", "/v1/jobs/%s/result" % iid)
    assert ri["spheres"] == r["spheres"] and ri["profile"] == r["profile"], "not bit for bit"
    assert ri["map"] == r["map"] and ri["stats"] == r["stats"]
    check_result(ri, sres, None, None, phi_deg)
    # without phi': 23.7; without the spheres the statics cannot be rechecked, views still draw
    pid = job_of(d, geo({"job": sid}, outputs=["profile"]))
    _, _, rp = d.json("GET", "/v1/jobs/%s/result" % pid)
    assert rp["phi_deg"] == 23.7 and "spheres" not in rp and rp["profile"] == r["profile"]
    check_views(d, pid)
    sph = job_of(d, geo({"job": sid}, outputs=["spheres"]))
    check_views(d, sph, missing=("profile", "k0"))
    st, _, j = d.json("GET", "/v1/jobs/%s/export?format=csv" % sph)
    assert st == 409, (st, j)
    assert d.stop() == 0, d.read_log()


def test_not_at_rest(env):
    """max_steps too small: measured as it is, converged false, a warning; not a failure."""
    d = env.daemon(workers=1)
    inline = {k: v for k, v in SPECIMEN.items() if k != "kind"}
    jid = job_of(d, geo({"spec": inline}, max_steps=1000))
    _, _, r = d.json("GET", "/v1/jobs/%s/summary" % jid)
    st = r["stats"]
    assert st["converged"] is False and st["steps"] == 1000 and st["stability"] > 1e-4, st
    assert any("not at rest" in w for w in r["warnings"]), r["warnings"]
    assert d.stop() == 0, d.read_log()


def test_refused_at_submit(env):
    d = env.daemon(workers=1)
    sid = job_of(d, SPECIMEN)
    s = {"job": sid}
    gpd.refused(d, geo({"job": "0" * 32}), "/specimen/job", "no job")
    gpd.refused(d, geo({}), "/specimen")
    gpd.refused(d, geo({"spec": dict(SPECIMEN, porosity=2)}), "/specimen/spec/porosity")
    # phi': both, an unknown job, a job of another kind, out of range
    gpd.refused(d, geo(s, phi_deg=30, phi_from={"job": "1" * 32}), "/phi_from", "not both")
    gpd.refused(d, geo(s, phi_from={"job": "1" * 32}), "/phi_from/job", "no job")
    gpd.refused(d, geo(s, phi_from={"job": sid}), "/phi_from/job", "of kind \"spheres-3d\"")
    gpd.refused(d, geo(s, phi_from={}), "/phi_from/job")
    gpd.refused(d, geo(s, phi_deg=90), "/phi_deg")
    # gravity along no axis, none at all; wall friction
    gpd.refused(d, geo(s, gravity=[1, 0, -9.81]), "/gravity", "along one axis")
    gpd.refused(d, geo(s, gravity=[0, 0, 0]), "/gravity", "along one axis")
    gpd.refused(d, geo(s, gravity=[0, -9.81]), "/gravity")
    gpd.refused(d, geo(s, wall_friction_deg=10), "/wall_friction_deg", "frictionless")
    # slabs and map cells
    gpd.refused(d, geo(s, slab=0.5), "/slab", "thicker than the packing")
    gpd.refused(d, geo(s, slab=1e-5), "/slab", code="too_large")
    gpd.refused(d, geo(s, map_cell=1e-4), "/map_cell", code="too_large")
    gpd.refused(d, geo(s, max_steps=10), "/max_steps")
    gpd.refused(d, geo(s, outputs=["curves"]), "/outputs/0")
    # the work bound: a large tiling settled for long
    big = dict(SPECIMEN, tiling=[8, 8, 8])
    gpd.refused(d, geo({"spec": {k: v for k, v in big.items() if k != "kind"}},
                   max_steps=10000000, slab=0.1), "/max_steps", code="too_large")
    st, _, lst = d.json("GET", "/v1/jobs?limit=500")
    assert sum(1 for j in lst["jobs"] if j["kind"] == KIND) == 0, lst
    assert d.stop() == 0, d.read_log()


def test_cancel_while_settling(env):
    d = env.daemon(workers=1)
    # 1-2 mm spheres settle slowly (a small time step): tens of seconds
    small = {"box": [0.008, 0.008, 0.008], "sieve": [[1, 0], [2, 100]], "sieve_units": "mm",
             "porosity": 0.5, "tiling": [2, 2, 2]}
    jid = d.submit(geo({"spec": small}, slab=0.002))
    deadline = time.time() + 60 * gpd.TIME_SCALE
    while True:
        job = d.job(jid)
        if job["progress"]["phase"] == "settling" and job["progress"]["detail"]["steps"] > 0:
            break
        assert job["status"] in ("queued", "running") and time.time() < deadline, job
        time.sleep(0.05)
    t0 = time.time()
    st, _, j = d.json("DELETE", "/v1/jobs/%s" % jid)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    inline = {k: v for k, v in SPECIMEN.items() if k != "kind"}
    quick = d.submit(geo({"spec": inline}))
    assert d.wait(quick, timeout=120)["status"] == "succeeded"
    assert time.time() - t0 < 60 * gpd.TIME_SCALE
    job = d.job(jid)
    assert job["status"] == "cancelled" and job["error"]["code"] == "cancelled", job
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_by_job_and_inline, test_not_at_rest, test_refused_at_submit,
              test_cancel_while_settling])
