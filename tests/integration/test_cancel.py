"""Cancel a running job (it stops within a second) and a queued one; SIGTERM requeues a running
job and the next start resumes it."""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402


def wait_idle(d, timeout):
    """Seconds until no worker is busy (health.workers_busy == 0)."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        st, _, h = d.json("GET", "/v1/health")
        if h["workers_busy"] == 0:
            return time.time() - t0
        time.sleep(0.02)
    raise AssertionError("workers still busy after %ss" % timeout)


def test_cancel_running(env):
    d = env.daemon(workers=1)
    jid = d.submit(gpd.LONG_2D)
    d.wait(jid, states=("running",), timeout=30, interval=0.01)
    time.sleep(0.3)
    st, _, j = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    gpd.check_job_object(j)
    assert j["finished_at"], j
    stopped_in = wait_idle(d, 5)
    assert stopped_in < 1.0 * gpd.TIME_SCALE, "the worker took %.2fs to stop" % stopped_in
    assert d.job(jid)["status"] == "cancelled"
    # the worker is free again: a new job runs to completion
    assert d.wait(d.submit(gpd.SMALL_2D))["status"] == "succeeded"
    assert d.stop() == 0, d.read_log()


def test_cancel_queued(env):
    d = env.daemon(workers=1)
    long_id = d.submit(gpd.LONG_2D)
    q = d.submit(gpd.SMALL_2D)
    st, _, j = d.json("DELETE", "/v1/jobs/" + q)
    assert st == 200 and j["status"] == "cancelled" and j["started_at"] is None, (st, j)
    d.json("DELETE", "/v1/jobs/" + long_id)
    wait_idle(d, 5)
    time.sleep(0.3)
    assert d.job(q)["status"] == "cancelled", "a cancelled queued job must never run"
    assert d.stop() == 0, d.read_log()


def test_sigterm_requeues(env):
    d = env.daemon(workers=1)
    jid = d.submit(gpd.LONG_2D)
    small = d.submit(gpd.SMALL_2D)
    d.wait(jid, states=("running",), timeout=30, interval=0.01)
    t0 = time.time()
    assert d.stop() == 0, d.read_log()
    assert time.time() - t0 < 5 * gpd.TIME_SCALE, "graceful stop took too long"
    d2 = env.daemon(workers=1)
    j = d2.job(jid)
    assert j["status"] in ("queued", "running"), j  # requeued, resumed first (oldest)
    d2.wait(jid, states=("running",), timeout=30, interval=0.01)
    st, _, j = d2.json("DELETE", "/v1/jobs/" + jid)
    assert st == 200, (st, j)
    assert d2.wait(small)["status"] == "succeeded"
    assert d2.stop() == 0, d2.read_log()


if __name__ == "__main__":
    gpd.main([test_cancel_running, test_cancel_queued, test_sigterm_requeues])
