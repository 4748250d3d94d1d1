"""A stalled PostgreSQL server freezes nothing (api.md "GET /v1/health", operations.md "Many
daemons on one PostgreSQL server").

test_stalled_server: the server's postmaster and every process of it are stopped (SIGSTOP)
while a daemon runs on it. /v1/health answers within a second, 503 with database
"unreachable", again and again; / and /v1/schema, which need no database, answer 200 within a
second; a request that needs the database answers (an error) instead of hanging. Then the
server is continued (SIGCONT): without a restart, the daemon's health is "ok" again within
seconds, and a submit, its job, its download and the list work as before.

test_restarted_server: the server stopped as a restart does (pg_ctl -m fast, every connection
closed) while a job runs, and started again once the job's run is over: the job succeeds, its
result stored after the outage, and no request after the restart answers 500.

Always on PostgreSQL (whatever GP_TEST_DB says): the test starts its own server (gpd.PgServer).
"""
import json
import os
import signal
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

gpd.PG, gpd.DB_MODE = True, "postgresql"  # this test is PostgreSQL's own
LIMIT_S = 1.0 * gpd.TIME_SCALE       # /v1/health, / and /v1/schema while the server is stopped
DB_ROUTE_LIMIT_S = 12.0 * gpd.TIME_SCALE  # a route that needs the database: an answer, not a hang
RECOVER_S = 15.0                      # health "ok" again after SIGCONT
TINY = dict(gpd.SMALL_2D, particles=20, contour_points=16, outputs=["grains"])
RESULT_3D = dict(gpd.SMALL_3D, tiling=[4, 4, 4], outputs=["spheres"])  # streamed (> 256 KB)
LONG_2D = dict(gpd.SMALL_2D, particles=40000, outputs=["grains"])  # runs about 3 s


def server_pids():
    """The postmaster of the test's server and every process it started."""
    with open(os.path.join(gpd.pg_server().data, "postmaster.pid")) as f:
        master = int(f.readline())
    kids = []
    for p in os.listdir("/proc"):
        if not p.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % p) as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        if ppid == master:
            kids.append(int(p))
    return [master] + kids


def signal_all(pids, sig):
    for p in pids:
        try:
            os.kill(p, sig)
        except ProcessLookupError:
            pass


def timed(d, path, timeout):
    t0 = time.time()
    try:
        st, h, b = d.request("GET", path, timeout=timeout)
    except Exception as e:  # noqa: BLE001 -- a timeout is the failure measured
        return None, None, time.time() - t0, repr(e)
    return st, h, time.time() - t0, b


def test_stalled_server(env):
    d = env.daemon(workers=1)
    jid = d.submit(RESULT_3D)
    assert d.wait(jid, timeout=120)["status"] == "succeeded"
    st, _, result = d.request("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200 and len(result) > 256 * 1024, (st, len(result))
    assert d.json("GET", "/v1/health")[2]["database"] == "ok"
    pid = d.proc.pid
    pids = server_pids()
    signal_all(pids, signal.SIGSTOP)
    t_stop = time.time()
    try:
        health = []
        for i in range(6):
            st, _, dt, b = timed(d, "/v1/health", timeout=10)
            health.append((st, dt))
            assert st == 503, (i, st, dt, b)
            j = json.loads(b)
            assert j["database"] == "unreachable" and j["status"] != "ok", j
            assert dt <= LIMIT_S, (i, dt)
            for path, ctype in (("/", "text/html"), ("/v1/schema", "application/schema+json")):
                st, h, dt, b = timed(d, path, timeout=10)
                assert st == 200 and h["Content-Type"].startswith(ctype), (path, st, dt)
                assert dt <= LIMIT_S, (path, dt)
            if i == 1:  # a route that needs the database: 503 to try again, not a hang
                st, h, dt, b = timed(d, "/v1/jobs/" + jid, timeout=30)
                print("  GET /v1/jobs/{id} while stopped: %s in %.2f s" % (st, dt))
                assert st == 503 and dt <= DB_ROUTE_LIMIT_S, (st, dt, b)
                assert h.get("Retry-After") == "5", h
                gpd.check_error_body(st, json.loads(b), "unavailable")
            time.sleep(0.5)
        print("  stopped %.1f s: /v1/health %s (slowest %.3f s); / and /v1/schema 200"
              % (time.time() - t_stop, sorted({s for s, _ in health}),
                 max(t for _, t in health)))
    finally:
        signal_all(pids, signal.SIGCONT)
    t_cont = time.time()
    while True:
        st, _, dt, b = timed(d, "/v1/health", timeout=10)
        if st == 200 and json.loads(b)["status"] == "ok":
            break
        assert time.time() - t_cont < RECOVER_S, (st, b)
        time.sleep(0.2)
    print("  continued: health ok again after %.2f s" % (time.time() - t_cont))
    assert d.proc.pid == pid and d.proc.poll() is None  # the same daemon, never restarted
    k = d.submit(TINY)
    assert d.wait(k, timeout=120)["status"] == "succeeded"
    st, _, again = d.request("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200 and again == result, st
    listed = [x["id"] for x in d.json("GET", "/v1/jobs")[2]["jobs"]]
    assert jid in listed and k in listed, listed
    assert d.stop() == 0, d.read_log()


def log_has(d, needle, timeout):
    deadline = time.time() + timeout
    while needle not in d.read_log():
        if time.time() > deadline:
            return False
        time.sleep(0.1)
    return True


def test_restarted_server(env):
    """A server restarted (pg_ctl -m fast) while a job runs: requests meanwhile answer 503 with
    Retry-After; the job, which finishes during the outage, stores its result once the server
    is back instead of failing store_error; and the connections the restart closed, idle in
    the daemon's threads, are replaced before use: no request after it answers 500."""
    d = env.daemon(workers=1, extra=["--log-level", "info"])
    for _ in range(40):  # every HTTP thread holds a connection of its own
        assert d.request("GET", "/v1/jobs?limit=1")[0] == 200
    jid = d.submit(LONG_2D)
    assert d.wait(jid, states=("running",) + gpd.FINAL, timeout=60)["status"] == "running"
    pg = gpd.pg_server()
    pg.halt()
    t_halt = time.time()
    try:
        st, h, dt, b = timed(d, "/v1/health", timeout=10)
        assert st == 503 and dt <= LIMIT_S and json.loads(b)["database"] == "unreachable", (st,
                                                                                        dt, b)
        st, h, b = d.request("POST", "/v1/jobs", body=TINY)
        assert st == 503 and h.get("Retry-After"), (st, b)
        gpd.check_error_body(st, json.loads(b), "unavailable")
        # the job's run ends while the server is down: its result waits
        waited = log_has(d, "its result waits for it", 180 * gpd.TIME_SCALE)
        assert waited, d.read_log()[-3000:]
        time.sleep(1.0)
    finally:
        pg.resume()
    down_s = time.time() - t_halt
    assert log_has(d, "its result stored after the outage", RECOVER_S), d.read_log()[-3000:]
    codes = [d.request("GET", "/v1/jobs/" + jid)[0] for _ in range(40)]
    codes += [d.request("GET", "/v1/jobs?limit=1")[0] for _ in range(40)]
    assert set(codes) == {200}, sorted(set(codes))
    j = d.job(jid)
    assert j["status"] == "succeeded", j
    st, _, result = d.request("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200 and json.loads(result)["stats"], st
    k = d.submit(TINY)
    assert d.wait(k, timeout=120)["status"] == "succeeded"
    print("  server down %.1f s under a running job: 503 meanwhile; after it the job succeeded "
          "(its result stored after the outage) and 80 requests all 200" % down_s)
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_stalled_server, test_restarted_server])
