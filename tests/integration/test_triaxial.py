"""The triaxial-3d kind: a test of a small spheres-3d specimen by job id and inline, at a fast
rate and a small strain (a few seconds); the result against the contract and against what can
be recomputed from its own curves (the peak, phi, q, p, the Mohr-Coulomb envelope); the same
specimen and test by job and inline give the same curves bit for bit; every SVG view; the csv
export against the curves; the refusals at submit (unknown job, a job not succeeded, of another
kind, the tiled part of an untiled specimen, bad confining stresses, strains and rates, an
inline spec's own problems, the work bound); cancel during the loading."""
import csv
import io
import json
import math
import os
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

KIND = "triaxial-3d"

# the specimen: a 6 mm box of 1-2 mm spheres (about 55; a fraction of a second)
SPECIMEN = {
    "kind": "spheres-3d",
    "seed": 7,
    "box": [0.006, 0.006, 0.006],
    "sieve": [[1, 0], [2, 100]],
    "sieve_units": "mm",
    "porosity": 0.5,
    "outputs": ["spheres"],
}

# a fast test: 5 % axial strain at 1 /s (consolidation takes most of its ~2 s)
FAST = {"confining_kpa": [50, 100], "axial_strain": 0.05, "strain_rate": 1.0}

TEST_KEYS = {"confining_kpa", "peak", "end", "dilatancy_deg", "e50_mpa", "inertial_number_max",
             "servo_error_max", "stability"}
CURVE_KEYS = ["axial_strain", "volumetric_strain", "sigma1_kpa", "sigma3_kpa", "q_kpa", "p_kpa",
              "stress_ratio", "coordination", "coordination_mechanical", "porosity", "stability",
              "inertial_number"]
CURVE_EXTRA = ["sigma1_lw_kpa", "sigma3_lw_kpa", "servo_error"]
VIEWS = ["stress-strain", "mohr", "section"]


def triax(specimen, **kw):
    spec = {"kind": KIND, "specimen": specimen}
    spec.update(FAST)
    spec.update(kw)
    return spec


def phi(r):
    return math.degrees(math.asin((r - 1) / (r + 1)))


def close(a, b, rel=1e-9, abs_=1e-12):
    return abs(a - b) <= max(rel * max(abs(a), abs(b)), abs_)


def mohr_coulomb(states):
    """The least-squares line t = a s + b through the peak states (sigma3, sigma1), b >= 0
    (else through the origin): phi, c (the core's rule, gp_triax.h)."""
    s = [(s1 + s3) / 2 for s3, s1 in states]
    t = [(s1 - s3) / 2 for s3, s1 in states]
    n = len(s)
    ms, mt = sum(s) / n, sum(t) / n
    sss = sum((x - ms) ** 2 for x in s)
    a, b = 0.0, -1.0
    if n > 1 and sss > 1e-24 * ms * ms:
        a = sum((x - ms) * (y - mt) for x, y in zip(s, t)) / sss
        b = mt - a * ms
    if not (b >= 0 and a >= 0):
        a, b = sum(x * y for x, y in zip(s, t)) / sum(x * x for x in s), 0.0
    return math.degrees(math.asin(a)), b / math.cos(math.asin(a))


def check_brief(b):
    """The brief of a triaxial job: headline phi_deg (no target: the spec asks for none)."""
    assert set(b) == {"particles", "seed", "headline"}, b
    assert set(b["headline"]) == {"name", "target", "achieved"}, b
    assert b["headline"]["name"] == "phi_deg" and b["headline"]["target"] is None, b


def specimen_job(d):
    jid = d.submit(SPECIMEN)
    job = d.wait(jid, timeout=60)
    assert job["status"] == "succeeded", job
    return jid


def check_curves(r):
    """The curves: the contract's arrays, and what they imply recomputed."""
    assert len(r["curves"]) == len(r["stats"]["tests"])
    for cu, t in zip(r["curves"], r["stats"]["tests"]):
        assert cu["confining_kpa"] == t["confining_kpa"]
        n = len(cu["axial_strain"])
        assert n >= 2
        for k in CURVE_KEYS + CURVE_EXTRA:
            assert len(cu[k]) == n and all(isinstance(v, float) for v in cu[k]), k
        assert cu["axial_strain"][0] == 0 and close(cu["axial_strain"][-1], r["axial_strain"],
                                                      1e-6)
        for i in range(n):
            s1, s3 = cu["sigma1_kpa"][i], cu["sigma3_kpa"][i]
            assert close(cu["q_kpa"][i], s1 - s3, 1e-9, 1e-9), (i, cu["q_kpa"][i], s1 - s3)
            assert close(cu["p_kpa"][i], (s1 + 2 * s3) / 3, 1e-9, 1e-9), i
            assert close(cu["stress_ratio"][i], s1 / s3, 1e-12), i
            assert 0 < cu["porosity"][i] < 1 and cu["coordination"][i] >= 0
        # the peak: the largest ratio of the samples, its strain, its phi
        kp = max(range(n), key=lambda i: (cu["stress_ratio"][i], -i))
        pk = t["peak"]
        assert pk["stress_ratio"] == cu["stress_ratio"][kp], (pk, kp)
        assert pk["axial_strain"] == cu["axial_strain"][kp]
        assert close(pk["phi_deg"], phi(pk["stress_ratio"]), 1e-12)
        assert pk["sigma1_kpa"] == cu["sigma1_kpa"][kp] and pk["sigma3_kpa"] == cu["sigma3_kpa"][kp]
        assert t["end"]["stress_ratio"] == cu["stress_ratio"][-1]
        assert close(t["end"]["phi_deg"], phi(cu["stress_ratio"][-1]), 1e-12)
        assert t["inertial_number_max"] == max(cu["inertial_number"][1:])
        assert t["servo_error_max"] == max(cu["servo_error"][1:])
        assert t["stability"] == max(cu["stability"][1:])
        # drained: the lateral stress holds sigma3 within a few percent
        if r["drainage"] == "drained":
            assert abs(pk["sigma3_kpa"] - t["confining_kpa"]) < 0.1 * t["confining_kpa"], pk


def check_result(r, spheres_job, n_tests):
    assert r["kind"] == KIND
    st = r["stats"]
    assert len(st["tests"]) == n_tests and st["particles"] == r["specimen"]["particles"]
    for t in st["tests"]:
        assert set(t) >= TEST_KEYS, sorted(t)
        assert set(t["peak"]) >= {"stress_ratio", "axial_strain", "phi_deg"}, t["peak"]
        assert set(t["end"]) >= {"stress_ratio", "phi_deg"}, t["end"]
        for k in TEST_KEYS - {"peak", "end"}:
            assert isinstance(t[k], float), (k, t[k])
        assert t["peak"]["stress_ratio"] >= t["end"]["stress_ratio"] and t["e50_mpa"] > 0
    mc = st["mohr_coulomb"]
    assert set(mc) == {"phi_deg", "cohesion_kpa", "residual"}, mc
    states = [(t["peak"]["sigma3_kpa"], t["peak"]["sigma1_kpa"]) for t in st["tests"]]
    ph, c = mohr_coulomb(states)
    assert close(mc["phi_deg"], ph, 1e-9) and close(mc["cohesion_kpa"], c, 1e-9, 1e-9), (mc, ph, c)
    assert mc["cohesion_kpa"] >= 0 and mc["residual"] >= 0
    if n_tests == 1:
        assert close(mc["phi_deg"], st["tests"][0]["peak"]["phi_deg"], 1e-9)
    assert set(r["timings"]) == {"specimen", "consolidation", "loading", "total"}
    assert isinstance(r["warnings"], list) and all(isinstance(w, str) for w in r["warnings"])
    # the specimen, rebuilt from its spec, is the job's: the same spheres, the same porosity
    assert r["specimen"]["particles"] == spheres_job["stats"]["particles"]
    assert r["specimen"]["porosity"] == spheres_job["stats"]["porosity"]["achieved"]
    if "curves" in r["outputs"]:
        check_curves(r)


def check_spheres(r):
    box = r["box"]
    assert len(r["spheres"]) == r["stats"]["particles"]
    for x, y, z, rad in r["spheres"]:
        assert rad > 0
        for v, b in zip((x, y, z), box):
            assert -rad <= v <= b + rad, (v, b)


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
    st, _, body = d.request("GET", "/v1/jobs/%s/svg?view=section&z=99" % jid)
    assert st == (409 if "section" in missing else 400), (st, body[:200])


def check_csv(d, jid, r):
    st, h, body = d.request("GET", "/v1/jobs/%s/export?format=csv" % jid)
    assert st == 200, (st, body[:300])
    assert h["Content-Type"].startswith("text/csv"), h["Content-Type"]
    assert h["Content-Disposition"] == 'attachment; filename="%s-csv.csv"' % jid, h
    rows = list(csv.reader(io.StringIO(body.decode())))
    assert rows[0] == ["confining_kpa"] + CURVE_KEYS + CURVE_EXTRA, rows[0]
    want = []
    for cu in r["curves"]:
        for i in range(len(cu["axial_strain"])):
            want.append([cu["confining_kpa"]] + [cu[k][i] for k in CURVE_KEYS + CURVE_EXTRA])
    got = [[float(v) for v in row] for row in rows[1:]]
    assert got == want, "the csv is not the curves"
    # the 3D sphere formats are not this kind's
    st, _, j = d.json("GET", "/v1/jobs/%s/export?format=lammps" % jid)
    assert st == 400 and "csv" in j["error"]["message"], j
    gpd.check_error_body(st, j, "invalid_parameter")


def test_by_job_and_inline(env):
    d = env.daemon(workers=2)
    sid = specimen_job(d)
    _, _, sres = d.json("GET", "/v1/jobs/%s/result" % sid)
    _, _, sspec = d.json("GET", "/v1/jobs/%s/spec" % sid)
    t0 = time.time()
    st, h, j = d.json("POST", "/v1/jobs", triax({"job": sid}))
    assert st == 201 and j["kind"] == KIND and j["status"] == "queued", (st, j)
    jid = j["id"]
    check_brief(j["brief"])
    # the stored spec holds the specimen job's effective spec beside its id
    _, _, spec = d.json("GET", "/v1/jobs/%s/spec" % jid)
    assert spec["specimen"]["job"] == sid and spec["specimen"]["part"] == "sample", spec
    assert spec["specimen"]["spec"] == sspec, (spec["specimen"]["spec"], sspec)
    assert spec["drainage"] == "drained" and spec["outputs"] == ["curves", "spheres"], spec
    # the same specimen inline (the test's seed given to it), one confinement
    inline = dict(SPECIMEN)
    del inline["kind"]
    seed = inline.pop("seed")
    iid = d.submit(triax({"spec": inline}, seed=seed, confining_kpa=[50]))
    phases = set()
    while True:
        job = d.job(jid)
        phases.add(job["progress"]["phase"])
        if job["status"] in gpd.FINAL:
            break
        det = job["progress"]["detail"]
        if job["progress"]["phase"] in ("consolidation", "loading"):
            assert det["tests"] == 2 and det["confining_kpa"] == [50, 100][det["test"]], det
        time.sleep(0.05)
    assert job["status"] == "succeeded", job
    assert time.time() - t0 < 60 * gpd.TIME_SCALE, "the fast test took too long"
    assert phases <= {"queued", "starting", "deposition", "compaction", "relaxation", "tiling",
                      "consolidation", "loading", "result", "done"}, phases
    check_brief(job["brief"])
    st, _, r = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200
    check_result(r, sres, 2)
    check_spheres(r)
    assert job["brief"]["particles"] == r["stats"]["particles"]
    assert job["brief"]["headline"]["achieved"] == r["stats"]["mohr_coulomb"]["phi_deg"]
    st, _, summ = d.json("GET", "/v1/jobs/%s/summary" % jid)
    assert st == 200 and "spheres" not in summ and summ["curves"] == r["curves"]
    check_views(d, jid)
    check_csv(d, jid, r)
    # inline: the same specimen, so the same first test, bit for bit
    assert d.wait(iid, timeout=60)["status"] == "succeeded"
    _, _, ispec = d.json("GET", "/v1/jobs/%s/spec" % iid)
    assert ispec["specimen"]["spec"] == sspec and "job" not in ispec["specimen"], ispec
    _, _, ir = d.json("GET", "/v1/jobs/%s/result" % iid)
    check_result(ir, sres, 1)
    assert ir["specimen"]["job"] is None and r["specimen"]["job"] == sid
    assert ir["curves"][0] == r["curves"][0], "the same specimen and test gave another curve"
    assert ir["stats"]["tests"][0] == r["stats"]["tests"][0]
    # the specimen job purged: the triaxial job keeps its result; its effective spec is still
    # a valid spec (its copy of the specimen's spec stands in for the job)
    assert d.request("DELETE", "/v1/jobs/%s?purge=1" % sid)[0] == 204
    assert d.json("GET", "/v1/jobs/%s/result" % jid)[0] == 200
    st, _, again = d.json("POST", "/v1/jobs", spec)
    assert st == 201, again
    assert d.stop() == 0, d.read_log()


def test_outputs_and_drainage(env):
    """Constant volume, curves only: no section; the spheres only: no curves, no csv."""
    d = env.daemon(workers=2)
    sid = specimen_job(d)
    _, _, sres = d.json("GET", "/v1/jobs/%s/result" % sid)
    cv = d.submit(triax({"job": sid}, confining_kpa=[80], drainage="constant_volume",
                        outputs=["curves"]))
    sp = d.submit(triax({"job": sid}, confining_kpa=[80], outputs=["spheres"]))
    assert d.wait(cv, timeout=60)["status"] == "succeeded"
    _, _, r = d.json("GET", "/v1/jobs/%s/result" % cv)
    assert r["drainage"] == "constant_volume" and "spheres" not in r
    check_result(r, sres, 1)
    # constant volume: the volumetric strain stays (nearly) 0
    assert max(abs(v) for v in r["curves"][0]["volumetric_strain"]) < 1e-4
    check_views(d, cv, missing=("section",))
    assert d.wait(sp, timeout=60)["status"] == "succeeded"
    _, _, r = d.json("GET", "/v1/jobs/%s/result" % sp)
    assert "curves" not in r
    check_spheres(r)
    check_views(d, sp, missing=("stress-strain",))
    st, _, j = d.json("GET", "/v1/jobs/%s/export?format=csv" % sp)
    assert st == 409, (st, j)
    gpd.check_error_body(st, j, "missing_output", "/outputs")
    assert d.stop() == 0, d.read_log()


def test_refused_at_submit(env):
    d = env.daemon(workers=1)
    sid = specimen_job(d)
    # an unknown job, a malformed id
    gpd.refused(d, triax({"job": "0" * 32}), "/specimen/job", "no job")
    gpd.refused(d, triax({"job": "xyz"}), "/specimen/job")
    # a job of another kind: a 2D job, a triaxial job
    fid = d.submit(dict(gpd.SMALL_2D, particles=20))
    assert d.wait(fid)["status"] == "succeeded"
    gpd.refused(d, triax({"job": fid}), "/specimen/job", "of kind \"fourier-voronoi-2d\"")
    tid = d.submit(triax({"job": sid}, confining_kpa=[50]))
    gpd.refused(d, triax({"job": tid}), "/specimen/job", "of kind \"%s\"" % KIND)
    # a job not succeeded: queued or running (the worker is busy), failed, cancelled
    slow = d.submit(dict(SPECIMEN, box=[0.03, 0.03, 0.03], seed=1))
    gpd.refused(d, triax({"job": slow}), "/specimen/job", "not succeeded")
    assert d.json("DELETE", "/v1/jobs/%s" % slow)[0] == 200
    gpd.refused(d, triax({"job": slow}), "/specimen/job", "is cancelled")
    bad = d.submit(dict(SPECIMEN, porosity=0.05))
    assert d.wait(bad, timeout=120)["status"] == "failed"
    gpd.refused(d, triax({"job": bad}), "/specimen/job", "is failed")
    assert d.wait(tid, timeout=60)["status"] == "succeeded"
    # the tiled part of an untiled specimen
    gpd.refused(d, triax({"job": sid, "part": "tiled"}), "/specimen/part", "not tiled")
    # the test's fields
    gpd.refused(d, triax({"job": sid}, confining_kpa=[0]), "/confining_kpa/0")
    gpd.refused(d, triax({"job": sid}, confining_kpa=[50, -1]), "/confining_kpa/1")
    gpd.refused(d, triax({"job": sid}, confining_kpa=[10001]), "/confining_kpa/0")
    gpd.refused(d, triax({"job": sid}, confining_kpa=[1, 2, 3, 4, 5, 6]), "/confining_kpa")
    gpd.refused(d, triax({"job": sid}, axial_strain=0), "/axial_strain")
    gpd.refused(d, triax({"job": sid}, axial_strain=0.6), "/axial_strain")
    gpd.refused(d, triax({"job": sid}, strain_rate=0), "/strain_rate")
    gpd.refused(d, triax({"job": sid}, drainage="undrained"), "/drainage")
    gpd.refused(d, triax({"job": sid}, outputs=["contacts"]), "/outputs/0")
    gpd.refused(d, triax({"job": sid}, material={"young": 1}), "/material/young")
    gpd.refused(d, triax({}), "/specimen")
    # an inline spec's own problems, at its fields
    gpd.refused(d, triax({"spec": dict(SPECIMEN, porosity=2)}), "/specimen/spec/porosity")
    gpd.refused(d, triax({"spec": dict(SPECIMEN, kind="fourier-voronoi-2d")}),
            "/specimen/spec/kind")
    # the work bound: a slow rate
    gpd.refused(d, triax({"job": sid}, strain_rate=1e-7), "/strain_rate", code="too_large")
    # nothing of these was stored
    st, _, lst = d.json("GET", "/v1/jobs?limit=500")
    assert sum(1 for j in lst["jobs"] if j["kind"] == KIND) == 1, lst
    assert d.stop() == 0, d.read_log()


def test_cancel_while_loading(env):
    d = env.daemon(workers=1)
    sid = specimen_job(d)
    jid = d.submit(triax({"job": sid}, confining_kpa=[50], axial_strain=0.3, strain_rate=0.02))
    deadline = time.time() + 60 * gpd.TIME_SCALE
    while True:
        job = d.job(jid)
        det = job["progress"]["detail"]
        if job["progress"]["phase"] == "loading" and det.get("axial_strain", 0) > 0:
            break
        assert job["status"] in ("queued", "running") and time.time() < deadline, job
        time.sleep(0.05)
    assert det["test"] == 0 and 0 < det["axial_strain"] < 0.3 and job["progress"]["eta_s"] > 0
    st, _, j = d.json("DELETE", "/v1/jobs/%s" % jid)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    time.sleep(0.5)
    job = d.job(jid)
    assert job["status"] == "cancelled" and job["error"]["code"] == "cancelled", job
    st, _, j = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 409, (st, j)
    # the worker is free again: a quick test runs
    quick = d.submit(triax({"job": sid}, confining_kpa=[50]))
    assert d.wait(quick, timeout=60)["status"] == "succeeded"
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_by_job_and_inline, test_outputs_and_drainage, test_refused_at_submit,
              test_cancel_while_loading])
