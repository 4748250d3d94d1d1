"""Submit -> poll -> succeeded -> result and every SVG view (parsed with xml.etree); listing with
cursors; health, schema, dashboard; same spec -> same result; clean SIGTERM exit."""
import json
import os
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402


def test_submit_poll_result_svg(env):
    d = env.daemon(workers=2)
    st, h, j = d.json("POST", "/v1/jobs", gpd.SMALL_2D)
    assert st == 201, (st, j)
    assert j["status"] == "queued" and len(j["id"]) == 32, j
    assert h["Location"] == "/v1/jobs/" + j["id"], h["Location"]
    gpd.check_job_object(j)
    jid = j["id"]

    # poll: the job object keeps its shape through every state
    seen = set()
    deadline = time.time() + 120
    while True:
        job = d.job(jid)
        gpd.check_job_object(job)
        seen.add(job["status"])
        if job["status"] in gpd.FINAL:
            break
        assert time.time() < deadline, job
        time.sleep(0.02)
    assert job["status"] == "succeeded", job
    assert job["kind"] == "fourier-voronoi-2d"
    assert job["started_at"] and job["finished_at"] and job["created_at"], job
    assert job["created_at"] <= job["started_at"] <= job["finished_at"], job
    assert job["created_at"].endswith("Z") and "T" in job["created_at"], job
    assert job["progress"]["fraction"] == 1.0 and job["error"] is None, job

    st, h, body = d.request("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200 and h["Content-Type"].startswith("application/json"), st
    r = json.loads(body)
    for k in ("stats", "timings", "grains", "cells"):
        assert k in r, k
    for k in ("imc_error", "imc_steps", "solid_fraction", "size_histogram",
              "orientation_histogram", "descriptors"):
        assert k in r["stats"], k
    for k in ("elongation", "roundness", "circularity", "regularity"):
        assert "mean" in r["stats"]["descriptors"][k], k
    for k in ("tessellation", "imc", "fill", "odec", "descriptors", "total"):
        assert k in r["timings"], k
    assert len(r["grains"]) > 0
    g = r["grains"][0]
    for k in ("id", "cell", "contour", "area", "orientation_deg", "descriptors", "discs"):
        assert k in g, k
    assert len(g["contour"][0]) == 2 and len(g["discs"][0]) == 3
    c = r["cells"][0]
    for k in ("id", "seed", "polygons", "area", "orientation_deg"):
        assert k in c, k

    for view in gpd.VIEWS_2D:
        st, h, body = d.request("GET", "/v1/jobs/%s/svg?view=%s" % (jid, view))
        assert st == 200, (view, st, body[:300])
        assert h["Content-Type"].startswith("image/svg+xml"), h["Content-Type"]
        root = ET.fromstring(body)
        assert root.tag in ("{http://www.w3.org/2000/svg}svg", "svg"), (view, root.tag)
    # an unknown view is a 400 that lists the valid ones
    st, _, j = d.json("GET", "/v1/jobs/%s/svg?view=nope" % jid)
    assert st == 400 and "packing" in j["error"]["message"], (st, j)
    gpd.check_error_body(st, j, "invalid_parameter")

    # the effective spec (extension) has the defaults filled in
    st, _, spec = d.json("GET", "/v1/jobs/%s/spec" % jid)
    assert st == 200 and spec["particles"] == gpd.SMALL_2D["particles"], spec
    assert "solid_fraction" in spec and "container" in spec, spec
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def results_of(d, specs):
    """The results of specs run on daemon d, without their timings."""
    ids = [d.submit(sp) for sp in specs]
    out = []
    for jid in ids:
        assert d.wait(jid)["status"] == "succeeded"
        r = json.loads(d.request("GET", "/v1/jobs/%s/result" % jid)[2])
        r.pop("timings")
        out.append(r)
    return out


def test_determinism(env):
    """The same spec and seed give the same result: twice on one daemon, and on daemons whose
    jobs run on 1 and on 3 threads (--job-threads: the 2D filling, ODEC and descriptors, the 3D
    DEM). SMALL_2D's grains carry ODEC discs and descriptors, SMALL_3D runs the DEM."""
    specs = [gpd.SMALL_2D, gpd.SMALL_2D, gpd.SMALL_3D]
    d = env.daemon(workers=2, extra=("--job-threads", "1"))
    one = results_of(d, specs)
    assert d.stop() == 0
    assert one[0] == one[1], "same spec and seed gave different results"
    d = env.daemon(workers=1, extra=("--job-threads", "3"))
    three = results_of(d, specs)
    assert d.stop() == 0
    assert one[0] == three[0], "the 2D result changed with the job's thread count"
    assert one[2] == three[2], "the 3D result changed with the job's thread count"


def test_list_pagination(env):
    d = env.daemon(workers=1)
    ids = [d.submit(dict(gpd.SMALL_2D, particles=20, seed=i)) for i in range(7)]
    for jid in ids:
        d.wait(jid)
    got, after = [], None
    while True:
        q = "/v1/jobs?limit=3" + ("&after=" + after if after else "")
        st, _, j = d.json("GET", q)
        assert st == 200 and set(j) == {"jobs", "next"}, (st, j)
        assert len(j["jobs"]) <= 3
        for job in j["jobs"]:
            gpd.check_job_object(job)
        got += [x["id"] for x in j["jobs"]]
        after = j["next"]
        if after is None:
            break
    assert got == list(reversed(ids)), "newest first, no duplicates, none missing"
    st, _, j = d.json("GET", "/v1/jobs?status=succeeded&limit=500")
    assert st == 200 and len(j["jobs"]) == 7 and j["next"] is None, j
    st, _, j = d.json("GET", "/v1/jobs?status=queued")
    assert st == 200 and j["jobs"] == [], j
    for bad in ("status=done", "limit=0", "limit=abc", "limit=100000", "after=nosuchjob"):
        st, _, j = d.json("GET", "/v1/jobs?" + bad)
        assert st == 400, (bad, st, j)
        gpd.check_error_body(st, j, "invalid_parameter")
    assert d.stop() == 0


def test_health_schema_dashboard(env):
    d = env.daemon(workers=3)
    st, _, h = d.json("GET", "/v1/health")
    assert st == 200 and h["status"] == "ok" and h["workers"] == 3, h
    assert h["queue_depth"] == 0, h
    st, hd, body = d.request("GET", "/v1/schema")
    assert st == 200, st
    s = json.loads(body)
    assert "$schema" in s and "fourier-voronoi-2d" in json.dumps(s), list(s)
    st, hd, body = d.request("GET", "/")
    assert st == 200 and hd["Content-Type"].startswith("text/html"), (st, hd["Content-Type"])
    assert b"<html" in body.lower() or b"<!doctype" in body.lower()
    st, _, _ = d.request("HEAD", "/v1/health")
    assert st == 200
    assert d.stop() == 0


def test_spheres_3d(env):
    d = env.daemon(workers=1)
    st, h, j = d.json("POST", "/v1/jobs", gpd.SMALL_3D)
    assert st == 201, (st, j)  # spheres-3d is always built in, like fourier-voronoi-2d
    assert j["status"] == "queued" and j["kind"] == "spheres-3d", j
    assert h["Location"] == "/v1/jobs/" + j["id"], h["Location"]
    gpd.check_job_object(j)
    job = d.wait(j["id"], timeout=150)
    assert job["status"] == "succeeded", job
    assert job["kind"] == "spheres-3d" and job["error"] is None, job
    st, _, r = d.json("GET", "/v1/jobs/%s/result" % j["id"])
    assert st == 200, st
    for k in ("porosity", "coordination_number", "fabric", "psd", "particles"):
        assert k in r["stats"], k
    for k in ("deposition", "compaction", "tiling", "total"):
        assert k in r["timings"], k
    assert r["spheres"] and len(r["spheres"][0]) == 4
    for view in ("section", "psd"):
        st, h, body = d.request("GET", "/v1/jobs/%s/svg?view=%s" % (j["id"], view))
        assert st == 200, (view, st, body[:300])
        ET.fromstring(body)
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_submit_poll_result_svg, test_determinism, test_list_pagination,
              test_health_schema_dashboard, test_spheres_3d])
