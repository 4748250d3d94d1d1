"""Limits of grainpackd against the real daemon: --job-timeout (a job that runs too long fails
with error code "timeout"; a DELETE stays "cancelled"), the exclusive lock on the SQLite file (a
second daemon on the same database refuses to start, the first keeps working), and a result
the database cannot store (the disk full) fails its job with a reason instead of committing
"succeeded" without a result or staying "running"; a result over the database's limit on one
value is stored in parts and reads back the same."""
import datetime
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

# IMC that runs for many seconds: the AD error cannot fall to 1e-9, and at N = 2000 it keeps
# gaining more than 1 % per stall window (120,000 steps) for longer than these tests wait.
ENDLESS_2D = {
    "kind": "fourier-voronoi-2d",
    "seed": 3,
    "particles": 2000,
    "imc": {"error": "AD", "threshold": 1e-9, "max_steps": 1000000000},
    "contour_points": 32,
    "outputs": ["grains"],
}

LOCK_MESSAGE = "is in use by another grainpackd"


def ts(s):
    return datetime.datetime.strptime(s, "%Y-%m-%dT%H:%M:%S.%fZ")


def health_latency(d):
    t0 = time.time()
    st, _, h = d.json("GET", "/v1/health", timeout=5)
    assert st == 200, (st, h)
    return time.time() - t0, h


def test_job_timeout(env):
    d = env.daemon(workers=1, extra=["--job-timeout", "2"])
    jid = d.submit(ENDLESS_2D)
    d.wait(jid, states=("running",), timeout=10, interval=0.01)
    t_run = time.time()
    worst = 0.0
    while True:
        lat, _ = health_latency(d)
        worst = max(worst, lat)
        j = d.job(jid)
        if j["status"] in gpd.FINAL:
            break
        assert time.time() - t_run < 10 * gpd.TIME_SCALE, j
        time.sleep(0.05)
    seen = time.time() - t_run
    gpd.check_job_object(j)
    assert j["status"] == "failed", j
    e = j["error"]
    assert e["code"] == "timeout", e
    assert "2 s" in e["message"] and "--job-timeout" in e["message"], e
    assert 'in phase "' in e["message"], e
    ran = (ts(j["finished_at"]) - ts(j["started_at"])).total_seconds()
    print("  timeout: ran %.3f s (started_at..finished_at), seen failed %.2f s after running; "
          "%s; health worst %.1f ms" % (ran, seen, e["message"], worst * 1e3))
    assert 2.0 <= ran <= 3.0 * gpd.TIME_SCALE, ran
    assert seen <= 4.0 * gpd.TIME_SCALE, seen
    # the daemon keeps serving, the worker is free again and a short job still succeeds
    lat, h = health_latency(d)
    assert lat < 0.1 * gpd.TIME_SCALE, lat
    assert h["workers_busy"] == 0 and h["running"] == 0, h
    assert worst < 0.5 * gpd.TIME_SCALE, worst
    st, _, j2 = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 409, (st, j2)
    assert d.wait(d.submit(gpd.SMALL_2D))["status"] == "succeeded"
    assert d.stop() == 0, d.read_log()


def test_delete_is_cancelled_not_timeout(env):
    d = env.daemon(workers=1, extra=["--job-timeout", "2"])
    jid = d.submit(ENDLESS_2D)
    d.wait(jid, states=("running",), timeout=10, interval=0.01)
    time.sleep(1.0)
    st, _, j = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    # past the limit: still cancelled, never turned into a timeout
    time.sleep(2.0)
    j = d.job(jid)
    assert j["status"] == "cancelled" and j["error"]["code"] == "cancelled", j
    _, h = health_latency(d)
    assert h["workers_busy"] == 0, h
    assert "over the job time limit" not in d.read_log(), d.read_log()
    assert d.stop() == 0, d.read_log()


def test_timeout_from_environment_and_zero(env):
    # GRAINPACK_JOB_TIMEOUT sets it; a flag wins over it; 0 = no limit
    d = env.daemon(workers=1, env={"GRAINPACK_JOB_TIMEOUT": "1"})
    jid = d.submit(ENDLESS_2D)
    j = d.wait(jid, timeout=10 * gpd.TIME_SCALE)
    assert j["status"] == "failed" and j["error"]["code"] == "timeout", j
    assert "1 s" in j["error"]["message"], j
    assert d.stop() == 0, d.read_log()
    d = env.daemon(workers=1, env={"GRAINPACK_JOB_TIMEOUT": "1"}, extra=["--job-timeout", "0"])
    jid = d.submit(ENDLESS_2D)
    d.wait(jid, states=("running",), timeout=10, interval=0.01)
    time.sleep(2.0)
    assert d.job(jid)["status"] == "running"
    assert d.json("DELETE", "/v1/jobs/" + jid)[0] == 200
    assert d.stop() == 0, d.read_log()
    r = subprocess.run([env.binary, "--job-timeout", "-1"], capture_output=True, timeout=10)
    assert r.returncode == 2 and b"--job-timeout" in r.stderr, r
    r = subprocess.run([env.binary, "--help"], capture_output=True, timeout=10)
    assert b"--job-timeout" in r.stdout and b"GRAINPACK_JOB_TIMEOUT" in r.stdout, r.stdout


def second_daemon(env, db):
    """Starts a daemon on db expecting a refusal: (exit status, stderr, seconds)."""
    t0 = time.time()
    r = subprocess.run([env.binary, "--listen", "127.0.0.1:0", "--db", db, "--workers", "1"],
                       capture_output=True, timeout=20)
    return r.returncode, r.stdout.decode(errors="replace"), r.stderr.decode(errors="replace"), \
        time.time() - t0


def test_second_daemon_refused(env):
    d = env.daemon(workers=2, extra=["--job-timeout", "0"])
    long_id = d.submit(ENDLESS_2D)
    d.wait(long_id, states=("running",), timeout=10, interval=0.01)
    started = d.job(long_id)["started_at"]
    # the same file by its path, by another spelling of it and through a symlink
    link = os.path.join(env.dir, "link.db")
    os.symlink(env.db, link)
    for db in (env.db, os.path.join(env.dir, ".", "jobs.db"), link):
        rc, out, err, secs = second_daemon(env, db)
        print("  second daemon on %s: exit %d in %.3f s: %s" % (db, rc, secs, err.strip()))
        assert rc != 0, (rc, out, err)
        assert LOCK_MESSAGE in err and db in err, err
        assert "listening on" not in out, out
    # the first daemon's job was not touched (not requeued, not restarted) and it keeps working
    j = d.job(long_id)
    assert j["status"] == "running" and j["started_at"] == started, j
    lat, h = health_latency(d)
    assert lat < 0.1 * gpd.TIME_SCALE and h["running"] == 1, (lat, h)
    assert d.wait(d.submit(gpd.SMALL_2D))["status"] == "succeeded"
    assert d.json("DELETE", "/v1/jobs/" + long_id)[0] == 200
    # the lock goes with the daemon: after a clean stop, and after kill -9
    assert d.stop() == 0, d.read_log()
    d2 = env.daemon(workers=1)
    assert d2.job(long_id)["status"] == "cancelled"
    d2.kill9()
    d3 = env.daemon(workers=1)
    assert d3.json("GET", "/v1/health")[0] == 200
    assert d3.stop() == 0, d3.read_log()


def run_unstorable(d, code, what):
    """Runs SMALL_2D on a daemon whose store cannot keep its result: the job fails with code,
    its result is 409, no worker stays busy. Returns (the job's error, /v1/health)."""
    jid = d.submit(gpd.SMALL_2D)
    j = d.wait(jid, timeout=60)
    gpd.check_job_object(j)
    assert j["status"] == "failed", j
    e = j["error"]
    assert e["code"] == code, e
    print("  %s: %s" % (what, e["message"]))
    st, _, b = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 409, (st, b)
    _, h = health_latency(d)
    assert h["running"] == 0 and h["workers_busy"] == 0, h
    return e, h


def result_and_exports(d, jid):
    """The result (timings left out: they are the run's own), the csv and vtk exports and the
    packing picture of job jid."""
    st, _, body = d.request("GET", "/v1/jobs/%s/result" % jid, timeout=60)
    assert st == 200, (st, body[:200])
    res = json.loads(body)
    res.pop("timings", None)
    out = [res, len(body)]
    for path in ("export?format=csv", "export?format=vtk", "svg?view=packing"):
        st, _, b = d.request("GET", "/v1/jobs/%s/%s" % (jid, path), timeout=60)
        assert st == 200, (path, st, b[:200])
        out.append(b)
    return out


# 700 grains of 128 contour points: a result of ~4.8 MB, past the 4 MiB at which a worker writes
# it to a temporary file, from which the store reads each part
SPILLED_2D = dict(gpd.SMALL_2D, particles=700, contour_points=128, outputs=["grains", "odec"])


def test_result_over_value_limit_in_parts(env):
    # the database's limit on one value lowered (a testing hook; 1 GB in SQLite and
    # PostgreSQL): a result and export pack in memory (20 kB a part) and one from its temporary
    # file (1 MB a part) are stored in parts and read back as one value -- the same result,
    # exports and picture as a daemon whose limit they are under
    ref = env.daemon(workers=1, db=os.path.join(env.dir, "ref.db"))
    jids = [ref.submit(s) for s in (gpd.SMALL_2D, SPILLED_2D)]
    want = []
    for jid in jids:
        assert ref.wait(jid, timeout=120)["status"] == "succeeded"
        want.append(result_and_exports(ref, jid))
    assert ref.stop() == 0, ref.read_log()
    for k, (spec, limit) in enumerate(((gpd.SMALL_2D, 20000), (SPILLED_2D, 1000000))):
        d = env.daemon(workers=1, db=os.path.join(env.dir, "parts%d.db" % k),
                       env={"GRAINPACK_TEST_SQLITE_MAX_LENGTH": str(limit)})
        check_in_parts(env, d, spec, limit, want[k], os.path.join(env.dir, "parts%d.db" % k))


def check_in_parts(env, d, spec, limit, want, path):
    jid = d.submit(spec)
    j = d.wait(jid, timeout=120)
    assert j["status"] == "succeeded", j
    got = result_and_exports(d, jid)
    size = got[1]
    parts = env.query_int("SELECT count(*) FROM value_parts WHERE what = 0", path)
    packs = env.query_int("SELECT count(*) FROM value_parts WHERE what = 1", path)
    print("  result %d bytes: part 0 and %d more; pack: part 0 and %d more" % (size, parts, packs))
    assert size > 3 * limit and parts == (size - 1) // (limit - 1024), (size, parts)
    assert spec is not SPILLED_2D or size > 4 * 2 ** 20, size  # past the spill threshold
    assert packs >= 1, packs
    assert got[0] == want[0], "the result read from parts differs"
    for k, what in enumerate(("csv", "vtk", "svg"), start=2):
        assert got[k] == want[k], "the %s from parts differs" % what
    # a purge removes every part (the maintenance thread frees them, a part a transaction)
    st, _, b = d.request("DELETE", "/v1/jobs/%s?purge=1" % jid)
    assert st == 204, (st, b)
    deadline = time.time() + 30
    while env.query_int("SELECT count(*) FROM value_parts", path) and time.time() < deadline:
        time.sleep(0.1)
    assert env.query_int("SELECT count(*) FROM value_parts", path) == 0
    assert d.stop() == 0, d.read_log()


def test_disk_full_fails_visibly(env):
    # the database capped at a few pages (a testing hook; SQLite answers SQLITE_FULL as on a
    # full disk): the job is small, its result is not; the commit is tried twice, then the job
    # fails with code store_error -- not left running
    d = env.daemon(workers=1, env={"GRAINPACK_TEST_SQLITE_MAX_PAGES": "10"})
    e, h = run_unstorable(d, "store_error", "disk full")
    assert "full" in e["message"] and "tried twice" in e["message"], e
    assert "retrying once" in d.read_log(), d.read_log()
    # health says that writes fail, though reads (and the small status update) pass
    assert h["status"] == "degraded" and h["database"] == "write_failed", h
    we = h["database_error"]
    assert "full" in we["message"] and we["count"] >= 2, we
    print("  health: %s" % json.dumps(we))
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_job_timeout, test_delete_is_cancelled_not_timeout,
              test_timeout_from_environment_and_zero, test_second_daemon_refused,
              test_result_over_value_limit_in_parts, test_disk_full_fails_visibly])
