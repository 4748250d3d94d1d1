"""The dashboard's data (issue 15) against the real daemon: every job object's "brief" (particles,
seed and the headline target with what was achieved, checked against the result itself), GET
/v1/jobs/{id}/summary (the result without its per-item arrays; 409 before success, 404 unknown),
progress that never goes back and says no time is left once a job was cancelled or failed, and a
database made before briefs (its jobs get theirs at the next start)."""
import os
import sqlite3
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

BULK = ("grains", "cells", "spheres", "contacts")


def result(d, jid):
    st, _, r = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200, (st, r)
    return r


def spec(d, jid):
    st, _, s = d.json("GET", "/v1/jobs/%s/spec" % jid)
    assert st == 200, (st, s)
    return s


def check_brief_before(d, job, particles):
    """A queued job's brief: from its effective spec, nothing achieved yet."""
    gpd.check_job_object(job)
    b, s = job["brief"], spec(d, job["id"])
    name = "solid_fraction" if s["kind"] == "fourier-voronoi-2d" else "porosity"
    assert b["seed"] == s["seed"], (b, s)
    assert b["headline"] == {"name": name, "target": s[name], "achieved": None}, (b, s)
    assert b["particles"] == particles, (b, particles)


def check_brief_after(d, jid, count):
    """A succeeded job's brief against its result: count(result) items, the headline's stats."""
    job = d.job(jid)
    assert job["status"] == "succeeded", job
    gpd.check_job_object(job)
    r, b = result(d, jid), job["brief"]
    n = count(r)
    name = b["headline"]["name"]
    achieved = r["stats"][name]["achieved"]
    assert b["particles"] == n, (b, n)
    assert b["headline"]["achieved"] == achieved, (b, achieved)
    assert b["seed"] == r["seed"] == spec(d, jid)["seed"], (b, r["seed"])
    # the list rows and the DELETE answer carry the same brief
    st, _, page = d.json("GET", "/v1/jobs?limit=500")
    row = [j for j in page["jobs"] if j["id"] == jid]
    assert st == 200 and row and row[0]["brief"] == b, (st, row, b)
    return job


def test_brief_2d(env):
    d = env.daemon(workers=1)
    jid = d.submit(gpd.SMALL_2D)
    st, _, j = d.json("GET", "/v1/jobs/" + jid)
    check_brief_before(d, j, gpd.SMALL_2D["particles"])
    assert d.wait(jid)["status"] == "succeeded"
    check_brief_after(d, jid, lambda r: len(r["grains"]))
    assert d.stop() == 0, d.read_log()


def test_brief_2d_sieve(env):
    """A sieve law: the grains' count follows from the curve; the brief has it at submit, as
    the run makes it."""
    d = env.daemon(workers=1)
    sp = dict(gpd.SMALL_2D, size={"law": "sieve", "sieve": [[0.08, 0], [0.15, 100]],
                                  "sieve_units": "m"})
    del sp["particles"]
    jid = d.submit(sp)
    job = d.job(jid)
    n = job["brief"]["particles"]
    assert isinstance(n, int) and n > 1, job
    check_brief_before(d, job, n)
    assert d.wait(jid)["status"] == "succeeded"
    check_brief_after(d, jid, lambda r: len(r["grains"]))
    assert result(d, jid)["stats"]["particles"]["target"] == n
    assert d.stop() == 0, d.read_log()


def test_brief_3d_default_seed(env):
    """No seed in the spec: the brief has the one the daemon chose, the effective spec's; the
    spheres are only known once the packing is made (tiled: the tiled count)."""
    d = env.daemon(workers=1)
    sp = dict(gpd.SMALL_3D, tiling=[2, 1, 1])
    del sp["seed"]
    jid = d.submit(sp)
    check_brief_before(d, d.job(jid), None)
    assert d.wait(jid)["status"] == "succeeded"
    job = check_brief_after(d, jid, lambda r: len(r["spheres"]))
    assert job["brief"]["particles"] == result(d, jid)["stats"]["particles"]
    assert d.stop() == 0, d.read_log()


def test_summary(env):
    d = env.daemon(workers=1)
    # unknown job, and a job not finished (running, then queued behind it)
    st, _, e = d.json("GET", "/v1/jobs/%s/summary" % ("0" * 32))
    assert st == 404, (st, e)
    gpd.check_error_body(st, e, "not_found")
    long_id = d.submit(gpd.LONG_2D)
    d.wait(long_id, states=("running",), timeout=30, interval=0.02)
    ids = {"2d": d.submit(gpd.SMALL_2D), "3d": d.submit(gpd.SMALL_3D)}
    for jid in (long_id, ids["2d"]):
        st, _, e = d.json("GET", "/v1/jobs/%s/summary" % jid)
        assert st == 409, (st, e)
        gpd.check_error_body(st, e, "not_ready")
    st, _, _ = d.json("DELETE", "/v1/jobs/" + long_id)
    assert st == 200
    st, _, e = d.json("GET", "/v1/jobs/%s/summary" % long_id)
    assert st == 409, (st, e)
    gpd.check_error_body(st, e, "not_ready")
    for jid in ids.values():
        assert d.wait(jid)["status"] == "succeeded"
        st, h, s = d.json("GET", "/v1/jobs/%s/summary" % jid)
        assert st == 200 and h["Content-Type"] == "application/json", (st, h)
        r = result(d, jid)
        assert not set(BULK) & set(s), sorted(s)
        assert set(BULK) & set(r), sorted(r)
        assert s["stats"] == r["stats"] and s["timings"] == r["timings"], jid
        assert s == {k: v for k, v in r.items() if k not in BULK}, jid
    assert d.stop() == 0, d.read_log()


def poll_monotone(d, jid, timeout=120):
    """Polls a job until it ends; asserts its fraction never goes down and that while it runs
    eta_s is a positive number once it has one. Returns the polls seen running."""
    seen, deadline = [], time.time() + timeout * gpd.TIME_SCALE
    while time.time() < deadline:
        j = d.job(jid)
        gpd.check_job_object(j)
        if j["status"] in gpd.FINAL:
            return seen, j
        if j["status"] == "running":
            p = j["progress"]
            if seen:
                assert p["fraction"] >= seen[-1]["fraction"], (seen[-1], p)
            assert p["eta_s"] is None or p["eta_s"] > 0, p
            seen.append(p)
        time.sleep(0.02)
    raise AssertionError("job %s did not end" % jid)


def test_progress_monotone(env):
    """A job through every phase, result included, on both kinds: the fraction only grows, an
    ETA is never 0 before the end; the end is "done", 1.0."""
    d = env.daemon(workers=1)
    for sp in (dict(gpd.SMALL_2D, particles=1500), dict(gpd.SMALL_3D, tiling=[3, 3, 3])):
        seen, j = poll_monotone(d, d.submit(sp))
        assert j["status"] == "succeeded", j
        assert j["progress"]["phase"] == "done" and j["progress"]["fraction"] == 1.0, j
        assert seen, "no poll saw the job running"
    assert d.stop() == 0, d.read_log()


def ended_progress(j, last):
    """A cancelled or failed job's progress: its last phase and fraction, no ETA."""
    p = j["progress"]
    assert p["eta_s"] is None, j
    assert p["phase"] not in ("queued", "done", "starting") and 0 < p["fraction"] < 1, j
    assert p["fraction"] >= last["fraction"], (last, p)


def test_ended_jobs_have_no_eta(env):
    d = env.daemon(workers=1, extra=["--job-timeout", "3"])
    # cancelled while running
    jid = d.submit(gpd.LONG_2D)
    while True:
        j = d.job(jid)
        if j["status"] == "running" and j["progress"]["eta_s"] is not None:
            break
        time.sleep(0.02)
    st, _, c = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 200 and c["status"] == "cancelled", (st, c)
    ended_progress(c, j["progress"])
    ended_progress(d.job(jid), j["progress"])
    # cancelled while queued: never ran, no ETA
    first, queued = d.submit(gpd.LONG_2D), d.submit(gpd.SMALL_2D)
    st, _, c = d.json("DELETE", "/v1/jobs/" + queued)
    assert st == 200 and c["progress"]["eta_s"] is None and c["progress"]["phase"] == "queued", c
    # failed (over --job-timeout) in its phase
    j = d.wait(first, timeout=60)
    assert j["status"] == "failed" and j["error"]["code"] == "timeout", j
    assert j["progress"]["eta_s"] is None and j["progress"]["fraction"] > 0, j
    assert d.stop() == 0, d.read_log()


def test_database_before_briefs(env):
    """A database whose jobs table has no brief column (made by an older daemon): the daemon
    adds it and fills in every job's brief at start, the achieved side from the result."""
    d = env.daemon(workers=1)
    done = d.submit(gpd.SMALL_2D)
    assert d.wait(done)["status"] == "succeeded"
    queued = d.submit(gpd.LONG_2D)
    d.wait(queued, states=("running",), timeout=30, interval=0.02)
    st, _, _ = d.json("DELETE", "/v1/jobs/" + queued)
    assert st == 200
    expect = {jid: d.job(jid)["brief"] for jid in (done, queued)}
    assert d.stop() == 0, d.read_log()
    with sqlite3.connect(env.db) as db:
        db.execute("ALTER TABLE jobs DROP COLUMN brief")
        cols = [r[1] for r in db.execute("PRAGMA table_info(jobs)")]
    assert "brief" not in cols, cols
    d2 = env.daemon(workers=1)
    for jid, b in expect.items():
        j = d2.job(jid)
        gpd.check_job_object(j)
        assert j["brief"] == b, (jid, j["brief"], b)
    check_brief_after(d2, done, lambda r: len(r["grains"]))
    assert d2.stop() == 0, d2.read_log()


if __name__ == "__main__":
    gpd.main([test_brief_2d, test_brief_2d_sieve, test_brief_3d_default_seed, test_summary,
              test_progress_monotone, test_ended_jobs_have_no_eta, test_database_before_briefs])
