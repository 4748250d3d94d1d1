"""Operating the daemon for months (api.md "Operations"): DELETE ?purge=1 gives the space back,
a purge during a streamed export never serves a half-deleted blob, --retain-days purges exactly
the jobs past the limit, --max-queued answers 503 queue_full with Retry-After until the queue
drains, and GET /metrics is valid Prometheus text (promtool) whose counters move as jobs run."""
import os
import re
import shutil
import sqlite3
import subprocess
import sys
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

# a job whose result and pack are large next to an empty database (~25 MB)
BIG_2D = {"kind": "fourier-voronoi-2d", "seed": 5, "particles": 4000, "contour_points": 128,
          "imc": {"max_steps": 0}, "outputs": ["grains", "odec", "descriptors", "cells"]}
TINY = dict(gpd.SMALL_2D, particles=20, contour_points=16, outputs=["grains"])
LONG = dict(gpd.LONG_2D)


def db_bytes(db):
    """The database's size on disk: the file and its write-ahead log."""
    return sum(os.path.getsize(p) for p in (db, db + "-wal") if os.path.exists(p))


def test_purge_gives_space_back(env):
    d = env.daemon(workers=1)
    gpd_ok = d.wait(d.submit(TINY))
    assert gpd_ok["status"] == "succeeded", gpd_ok
    time.sleep(0.5)
    before = db_bytes(env.db)
    jid = d.submit(BIG_2D)
    j = d.wait(jid, timeout=300)
    assert j["status"] == "succeeded", j
    grown = db_bytes(env.db) - before
    assert grown > 5e6, grown
    # not finished: purge refused, nothing removed
    long_id = d.submit(LONG)
    d.wait(long_id, states=("running",), timeout=60)
    st, _, e = d.json("DELETE", "/v1/jobs/%s?purge=1" % long_id)
    assert st == 409, (st, e)
    gpd.check_error_body(st, e, "not_finished")
    assert d.json("DELETE", "/v1/jobs/" + long_id)[0] == 200
    # finished: without purge still 409 already_finished (api.md), with purge 204
    st, _, e = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 409 and e["error"]["code"] == "already_finished", (st, e)
    st, _, b = d.request("DELETE", "/v1/jobs/%s?purge=1" % jid)
    assert st == 204 and b == b"", (st, b)
    for path in ("", "/result", "/spec", "/export?format=csv", "/svg?view=packing"):
        st, _, e = d.json("GET", "/v1/jobs/%s%s" % (jid, path))
        assert st == 404, (path, st, e)
    assert d.json("DELETE", "/v1/jobs/%s?purge=1" % jid)[0] == 404
    listed = [x["id"] for x in d.json("GET", "/v1/jobs")[2]["jobs"]]
    assert jid not in listed and gpd_ok["id"] in listed, listed
    deadline = time.time() + 10
    while True:
        after = db_bytes(env.db)
        if after - before <= 0.1 * grown or time.time() > deadline:
            break
        time.sleep(0.2)
    print("  purge: the job grew the database by %.1f MB; %.1f MB of it left after the purge"
          % (grown / 1e6, (after - before) / 1e6))
    assert after - before <= 0.1 * grown, (before, grown, after)
    assert d.stop() == 0, d.read_log()


def test_purge_during_export(env):
    d = env.daemon(workers=1)
    jid = d.submit(BIG_2D)
    assert d.wait(jid, timeout=300)["status"] == "succeeded"
    url = d.url + "/v1/jobs/%s/export?format=vtk" % jid
    with urllib.request.urlopen(url, timeout=60) as r:
        whole = r.read()
    assert len(whole) > 1e6, len(whole)
    # a slow reader: 64 KB, then the purge, then the rest
    r = urllib.request.urlopen(url, timeout=60)
    got = r.read(65536)
    st, _, b = d.request("DELETE", "/v1/jobs/%s?purge=1" % jid)
    assert st == 204, (st, b)
    try:
        while True:
            chunk = r.read(65536)
            if not chunk:
                break
            got += chunk
        complete = True
    except Exception as e:  # noqa: BLE001 -- a cleanly failed download is allowed
        complete = False
        print("  the download in progress failed cleanly: %r" % e)
    r.close()
    # what was served is the export as it was, never part of another blob
    assert whole.startswith(got), (len(got), len(whole))
    if complete:
        assert got == whole, (len(got), len(whole))
        print("  the download in progress finished: %d bytes, identical" % len(got))
    assert d.json("GET", "/v1/jobs/" + jid)[0] == 404
    assert d.json("GET", "/v1/health")[2]["status"] == "ok"
    assert d.stop() == 0, d.read_log()


def test_retention(env):
    d = env.daemon(workers=2)
    ids = [d.submit(dict(TINY, seed=s)) for s in range(6)]
    for jid in ids:
        assert d.wait(jid)["status"] == "succeeded"
    cancelled = d.submit(LONG)
    d.wait(cancelled, states=("running",), timeout=60)
    assert d.json("DELETE", "/v1/jobs/" + cancelled)[0] == 200
    queued = None
    assert d.stop() == 0, d.read_log()
    # age some of them (the daemon is stopped): 10 days, 6 days, 4 days ago; 3 stay recent
    now = time.time()

    def stamp(days):
        t = now - days * 86400
        return time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(t)) + ".000Z"

    ages = {ids[0]: 10, ids[1]: 6, ids[2]: 4, cancelled: 8}
    for jid, days in ages.items():  # (SQLite or PostgreSQL: gpd.Env.execute)
        env.execute("UPDATE jobs SET created_at=?, finished_at=? WHERE id=?",
                    (stamp(days + 0.01), stamp(days), jid))
    d = env.daemon(workers=1, extra=("--retain-days", "5"))
    queued = d.submit(TINY)  # new and unfinished: never a candidate
    gone = {ids[0], ids[1], cancelled}
    deadline = time.time() + 20
    while time.time() < deadline:
        listed = {x["id"] for x in d.json("GET", "/v1/jobs?limit=500")[2]["jobs"]}
        if not (gone & listed):
            break
        time.sleep(0.2)
    assert not (gone & listed), gone & listed
    kept = set(ids[2:]) | {queued}
    assert kept <= listed, (kept, listed)
    print("  retention 5 days: purged %d of %d jobs (10, 8 and 6 days old), kept %d" % (
        len(gone), len(ids) + 2, len(kept)))
    assert d.stop() == 0, d.read_log()
    # the environment variable sets it too
    d = env.daemon(workers=1, env={"GRAINPACK_RETAIN_DAYS": "3"})
    deadline = time.time() + 20
    while time.time() < deadline:
        listed = {x["id"] for x in d.json("GET", "/v1/jobs?limit=500")[2]["jobs"]}
        if ids[2] not in listed:
            break
        time.sleep(0.2)
    assert ids[2] not in listed and set(ids[3:]) <= listed, listed
    assert d.stop() == 0, d.read_log()


def test_queue_full(env):
    d = env.daemon(workers=1, extra=("--max-queued", "3"))
    running = d.submit(LONG)
    d.wait(running, states=("running",), timeout=60)
    queued = [d.submit(dict(TINY, seed=s)) for s in range(3)]
    st, h, e = d.json("POST", "/v1/jobs", TINY)
    assert st == 503, (st, e)
    gpd.check_error_body(st, e, "queue_full")
    assert "3" in e["error"]["message"], e
    retry = h.get("Retry-After")
    assert retry is not None and int(retry) >= 1, dict(h)
    print("  queue_full at 3 queued: Retry-After %s; %s" % (retry, e["error"]["message"]))
    # the queue drains: submits are accepted again
    assert d.json("DELETE", "/v1/jobs/" + running)[0] == 200
    for jid in queued:
        assert d.wait(jid)["status"] == "succeeded"
    assert d.wait(d.submit(TINY))["status"] == "succeeded"
    assert d.stop() == 0, d.read_log()


METRIC_LINE = re.compile(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[^}]*\})? (\S+)$')


def scrape(d):
    st, h, b = d.request("GET", "/metrics")
    assert st == 200, (st, b[:200])
    assert h.get("Content-Type", "").startswith("text/plain; version=0.0.4"), dict(h)
    values = {}
    for line in b.decode().splitlines():
        if not line or line.startswith("#"):
            continue
        m = METRIC_LINE.match(line)
        assert m, line
        values[m.group(1) + (m.group(2) or "")] = float(m.group(3))
    return b, values


def promtool_check(text):
    tool = shutil.which("promtool")
    if not tool:
        print("  promtool not installed: the text format is checked by this test alone")
        return
    p = subprocess.run([tool, "check", "metrics"], input=text, capture_output=True, timeout=60)
    # promtool exits 0 when the exposition is valid; lint remarks go to stdout/stderr
    assert p.returncode == 0, (p.returncode, p.stdout, p.stderr)


def test_metrics(env):
    d = env.daemon(workers=1)
    text0, m0 = scrape(d)
    promtool_check(text0)
    for key in ("grainpack_queue_depth", "grainpack_workers_busy", "grainpack_workers",
                "grainpack_database_bytes"):
        assert key in m0, (key, sorted(m0))
    jids = [d.submit(dict(TINY, seed=s)) for s in range(3)]
    for jid in jids:
        d.wait(jid)
    d3 = d.submit(gpd.SMALL_3D)
    assert d.wait(d3, timeout=120)["status"] == "succeeded"
    d.json("POST", "/v1/jobs", {"kind": "nope"})

    def val(m, name, **labels):
        want = "{" + ",".join('%s="%s"' % kv for kv in sorted(labels.items())) + "}"
        for k, v in m.items():
            if k.split("{")[0] == name and set(want[1:-1].split(",")) <= set(
                    k[len(name) + 1:-1].split(",")):
                return v
        return 0.0

    # a request is counted when its connection has sent the last byte (libmicrohttpd's
    # completion), which may come a moment after the client has read the answer
    deadline = time.time() + 5
    while True:
        text1, m1 = scrape(d)
        if val(m1, "grainpack_http_requests_total", route="/v1/jobs", status="422") or \
                time.time() > deadline:
            break
        time.sleep(0.05)
    promtool_check(text1)

    k2, k3 = "fourier-voronoi-2d", "spheres-3d"
    assert val(m1, "grainpack_jobs", kind=k2, status="succeeded") == 3, m1
    assert val(m1, "grainpack_jobs", kind=k3, status="succeeded") == 1, m1
    assert val(m1, "grainpack_jobs_finished_total", kind=k2, status="succeeded") - val(
        m0, "grainpack_jobs_finished_total", kind=k2, status="succeeded") == 3
    assert val(m1, "grainpack_job_duration_seconds_count", kind=k2, phase="total") == 3, m1
    assert val(m1, "grainpack_job_duration_seconds_count", kind=k3, phase="deposition") == 1
    assert val(m1, "grainpack_job_duration_seconds_sum", kind=k3, phase="total") > 0
    posts = val(m1, "grainpack_http_requests_total", route="/v1/jobs", status="201")
    assert posts == 4, posts
    assert val(m1, "grainpack_http_requests_total", route="/v1/jobs", status="422") == 1
    assert m1["grainpack_database_bytes"] > m0["grainpack_database_bytes"]
    # cheap enough to scrape every second: 200 scrapes
    t0 = time.time()
    for _ in range(200):
        scrape(d)
    dt = (time.time() - t0) / 200
    print("  /metrics: %d bytes, %.2f ms a scrape" % (len(text1), 1e3 * dt))
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_purge_gives_space_back, test_purge_during_export, test_retention,
              test_queue_full, test_metrics])
