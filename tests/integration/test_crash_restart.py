"""kill -9 with jobs queued and running, restart: every job reaches a final state, none lost.
A job interrupted STORE_MAX_ATTEMPTS (3) times fails with error code "interrupted"."""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402


def test_kill9_restart(env):
    d = env.daemon(workers=2)
    ids = [d.submit(dict(gpd.SMALL_2D, seed=100 + i, particles=80)) for i in range(8)]
    # catch a moment with jobs running and jobs queued
    deadline = time.time() + 30
    while True:
        st, _, j = d.json("GET", "/v1/jobs?limit=500")
        states = [x["status"] for x in j["jobs"]]
        if "running" in states and "queued" in states:
            break
        assert time.time() < deadline, states
        time.sleep(0.005)
    d.kill9()
    d2 = env.daemon(workers=2)
    st, _, j = d2.json("GET", "/v1/jobs?limit=500")
    assert sorted(x["id"] for x in j["jobs"]) == sorted(ids), "a job was lost"
    for jid in ids:
        job = d2.wait(jid, timeout=120)
        assert job["status"] == "succeeded", job
        st, _, r = d2.json("GET", "/v1/jobs/%s/result" % jid)
        assert st == 200 and r["grains"], st
    # results survive another crash unchanged
    st, _, before = d2.json("GET", "/v1/jobs/%s/result" % ids[0])
    d2.kill9()
    d3 = env.daemon(workers=1)
    st, _, after = d3.json("GET", "/v1/jobs/%s/result" % ids[0])
    assert st == 200 and after == before
    assert d3.stop() == 0, d3.read_log()


def test_interrupted_three_times_fails(env):
    jid = None
    for attempt in range(3):
        d = env.daemon(workers=1)
        if jid is None:
            jid = d.submit(gpd.LONG_2D)
        d.wait(jid, states=("running",), timeout=30, interval=0.01)
        d.kill9()
    d = env.daemon(workers=1)
    j = d.job(jid)
    assert j["status"] == "failed", j
    assert j["error"]["code"] == "interrupted" and "3 times" in j["error"]["message"], j
    gpd.check_job_object(j)
    st, _, h = d.json("GET", "/v1/health")
    assert h["running"] == 0 and h["queue_depth"] == 0, h
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_kill9_restart, test_interrupted_three_times_fails])
