"""Many daemons, one queue (issue #18): daemons sharing one PostgreSQL server.

test_two_daemons_one_killed: two daemons (lease 3 s) on one database; 40 small jobs, 2D and 3D,
submitted to either; one daemon SIGKILLed while it runs jobs. Every job ends succeeded, its
result written exactly once (jobs.results_written = 1, read with psql), the jobs the dead
daemon was running taken over by the other once their lease lapsed and counted as a second
attempt; both daemons (the survivor and a restarted one) list the same jobs, byte for byte.

test_cancel_reaches_other_daemon: a job running on one daemon, DELETE sent to the other: the
runner stops it (its worker is free again) within 2 s, and nothing of it is written after.

test_lapsed_lease_rule: jobs left running by a daemon of another host (owner rewritten in SQL
after a kill -9) are not touched at start-up while their lease holds; once it lapses, the one
claimed 3 times fails with "interrupted", the one claimed once is taken over (attempt 2) and
succeeds -- the restart rule across hosts.

Always on PostgreSQL (whatever GP_TEST_DB says): the test starts its own server (gpd.PgServer).
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

gpd.PG, gpd.DB_MODE = True, "postgresql"  # this test is PostgreSQL's own
LEASE = "3"
TINY_2D = dict(gpd.SMALL_2D, particles=40, contour_points=16)


def sql(env, q):
    """Rows of q on the test's database, as lists of strings."""
    out = gpd.pg_server().psql(q, env.pg_dbs[env.db])
    return [line.split("|") for line in out.splitlines() if line]


def owned_by(env, d, status="running"):
    """Ids of the jobs of the given status whose owner is daemon d (its pid in the owner id)."""
    rows = sql(env, "SELECT id FROM jobs WHERE status='%s' AND split_part(owner, '/', 3) = '%d'"
               % (status, d.proc.pid))
    return {r[0] for r in rows}


def specs(n):
    """n small specs, every fourth a 3D packing, each with its own seed."""
    out = []
    for i in range(n):
        if i % 4 == 3:
            out.append(dict(gpd.SMALL_3D))  # (its seed packs; others may be infeasible)
        else:
            out.append(dict(TINY_2D, seed=200 + i))
    return out


def listing(d):
    st, _, j = d.json("GET", "/v1/jobs?limit=500")
    assert st == 200 and j["next"] is None, (st, j)
    return j["jobs"]


def test_two_daemons_one_killed(env):
    a = env.daemon(workers=2, extra=["--lease", LEASE])
    b = env.daemon(workers=2, extra=["--lease", LEASE])
    ids = [(a if i % 2 else b).submit(s) for i, s in enumerate(specs(40))]
    # both see every job at once (one queue)
    assert {x["id"] for x in listing(a)} == set(ids) == {x["id"] for x in listing(b)}
    # kill a while it runs jobs
    deadline = time.time() + 60
    while True:
        on_a = owned_by(env, a)
        if len(on_a) >= 2 or (on_a and time.time() > deadline - 50):
            break
        assert time.time() < deadline, "daemon a never ran a job"
        time.sleep(0.02)
    a.kill9()
    t_kill = time.time()
    # what a was running when it died, read again now: a job of the snapshot above may have
    # finished (and a taken another) between that query and the kill
    on_a = owned_by(env, a)
    assert on_a, "daemon a died with no job running"
    # a's jobs still show running (their leases hold them) until b takes them over
    ids_sql = ", ".join("'%s'" % j for j in sorted(on_a))  # ids made by the daemon: hex only
    while True:
        left = sql(env, "SELECT count(*) FROM jobs WHERE id IN (%s) AND status = 'running' "
                        "AND split_part(owner, '/', 3) = '%d'" % (ids_sql, a.proc.pid))
        if left[0][0] == "0":
            break
        assert time.time() - t_kill < 60, "a's jobs were never taken over"
        time.sleep(0.05)
    t_take = time.time() - t_kill
    for jid in on_a:
        j = b.wait(jid, timeout=120 * gpd.TIME_SCALE)
        assert j["status"] == "succeeded", j
    t_over = time.time() - t_kill
    for jid in ids:
        j = b.wait(jid, timeout=180 * gpd.TIME_SCALE)
        assert j["status"] == "succeeded", j
        gpd.check_job_object(j)
    rows = {r[0]: r[1:] for r in sql(env, "SELECT id, attempts, results_written, "
                                          "split_part(owner, '/', 3) FROM jobs")}
    assert set(rows) == set(ids), "a job was lost or added"
    # exactly one result each; attempts: 1, or 2 for a job a was running when it died
    assert all(r[1] == "1" for r in rows.values()), rows
    twice = {jid for jid, r in rows.items() if r[0] == "2"}
    assert all(r[0] in ("1", "2") for r in rows.values()), rows
    assert twice and twice <= set(rows) and on_a <= twice, (on_a, twice)
    assert all(rows[jid][2] == str(b.proc.pid) for jid in twice), rows
    st, _, r1 = b.json("GET", "/v1/jobs/%s/result" % sorted(twice)[0])
    assert st == 200 and (r1.get("grains") or r1.get("spheres")), st
    # both daemons list the same jobs: the survivor and a new daemon on the same database
    c = env.daemon(workers=1, extra=["--lease", LEASE])
    lb, lc = listing(b), listing(c)
    assert lb == lc and len(lb) == 40, "the daemons list different jobs"
    print("  40 jobs on 2 daemons; daemon a killed running %d; b took them over %.1f s and had "
          "finished them %.1f s after the kill (lease %s s); attempts: %d jobs twice, %d once; "
          "every result written once" % (len(on_a), t_take, t_over, LEASE, len(twice),
                                         40 - len(twice)))
    for d in (b, c):
        assert d.stop() == 0, d.read_log()


def test_cancel_reaches_other_daemon(env):
    a = env.daemon(workers=1, extra=["--lease", LEASE])
    b = env.daemon(workers=1, extra=["--lease", LEASE])
    jid = a.submit(gpd.LONG_2D)
    a.wait(jid, states=("running",), timeout=30, interval=0.01)
    # wherever it runs, the DELETE goes to the other daemon
    deadline = time.time() + 10
    while True:
        runner = a if owned_by(env, a) else b if owned_by(env, b) else None
        if runner:
            break
        assert time.time() < deadline
        time.sleep(0.01)
    other = b if runner is a else a
    time.sleep(1.0)  # well into its run
    t0 = time.time()
    st, _, j = other.json("DELETE", "/v1/jobs/" + jid)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    while True:  # stopped: the runner's worker is free again
        h = runner.json("GET", "/v1/health")[2]
        if h["workers_busy"] == 0:
            break
        assert time.time() - t0 < 10, h
        time.sleep(0.01)
    dt = time.time() - t0
    print("  a DELETE sent to one daemon stopped the job on the other in %.3f s" % dt)
    assert dt < 2.0 * gpd.TIME_SCALE, dt
    assert "cancelled by another daemon" in runner.read_log(), runner.read_log()
    time.sleep(0.5)
    for d in (a, b):
        j = d.job(jid)
        assert j["status"] == "cancelled" and j["error"]["code"] == "cancelled", j
    assert sql(env, "SELECT results_written FROM jobs")[0][0] == "0"
    # both still work
    for d in (a, b):
        assert d.wait(d.submit(TINY_2D))["status"] == "succeeded"
    for d in (a, b):
        assert d.stop() == 0, d.read_log()


def test_lapsed_lease_rule(env):
    a = env.daemon(workers=1, extra=["--lease", LEASE])
    j1 = a.submit(gpd.LONG_2D)
    a.wait(j1, states=("running",), timeout=30, interval=0.01)
    j2 = a.submit(TINY_2D)  # queued behind it (one worker)
    a.kill9()
    # as if both had been running on a daemon of another host, whose leases run 3 s more
    gpd.pg_server().psql(
        "UPDATE jobs SET status='running', attempts = CASE WHEN id = :'j1' THEN 3 ELSE 1 END, "
        "owner = 'elsewhere/0/1/' || id, lease_until = now() + interval '3 s' "
        "WHERE id IN (:'j1', :'j2');\n", env.pg_dbs[env.db], {"j1": j1, "j2": j2})
    t0 = time.time()
    b = env.daemon(workers=1, extra=["--lease", LEASE])
    assert [b.job(j)["status"] for j in (j1, j2)] == ["running", "running"], "taken too early"
    f = b.wait(j1, timeout=60)
    t_fail = time.time() - t0
    assert f["status"] == "failed" and f["error"]["code"] == "interrupted", f
    assert "3 times" in f["error"]["message"], f
    s = b.wait(j2, timeout=60)
    assert s["status"] == "succeeded", s
    rows = {r[0]: r[1:] for r in sql(env, "SELECT id, attempts, results_written FROM jobs")}
    assert rows[j1] == ["3", "0"] and rows[j2] == ["2", "1"], rows
    print("  lapsed leases: the job at its 3rd attempt failed (interrupted) %.1f s after the "
          "other host's lease began its last 3 s; the other was taken over as attempt 2" % t_fail)
    assert t_fail > 2.0, t_fail  # not before the lease lapsed (3 s from the update)
    assert b.stop() == 0, b.read_log()


if __name__ == "__main__":
    gpd.main([test_two_daemons_one_killed, test_cancel_reaches_other_daemon,
              test_lapsed_lease_rule])
