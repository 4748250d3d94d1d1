#!/usr/bin/env python3
"""bench_queue.py -- the job queue under load: SQLite (one daemon) and PostgreSQL (1, 2, 4
daemons on one server), and status polls per second against a daemon on each.

    python3 bench/bench_queue.py build/server/grainpackd [--jobs 400] [--workers 2]
                                 [--poll-seconds 5] [--connections 50]

Queue rows: --jobs trivially small jobs are put in the queue while no daemon runs (copies of
one submitted job, made in SQL), then the daemons start together, each with --workers workers,
and drain it. Two kinds of job: "2D tiny", a 10-grain 2D specimen without IMC steps (a few ms
of CPU, but its fill phase polls its threads every 50 ms: about 0.1 s a job whatever the
machine, so one worker does at most ~8 a second); and "no-op", a job of a kind this build does
not have, which a worker claims and fails at once (not_implemented): the queue alone -- claim,
final write -- with nothing run.
claimed/s = jobs / (last started_at - first started_at): the rate at which the queue hands out
jobs; done/s = jobs / (last finished_at - first started_at): claim, run and result commit. The
error columns: jobs not succeeded, and jobs whose result was written other than once
(PostgreSQL's jobs.results_written; SQLite has one daemon, '-'), both 0 when the queue is right.
Poll rows: wrk (Debian package wrk), GET /v1/jobs/{id} of a succeeded job, --connections
connections for --poll-seconds, against one daemon on each back end.

The PostgreSQL server is the tests' own (tests/integration/gpd.py PgServer: a temporary
initdb on 127.0.0.1, in the system's temporary directory), here with fsync on, as durable as
SQLite's synchronous=FULL (its file in the same directory). On a machine with few cores the
daemons share them with the server and with each other: read the rows with the core count and
load printed in the header. One table; python3 standard library only.
"""
import argparse
import os
import sqlite3
import subprocess
import sys
import time

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "tests", "integration"))
import gpd  # noqa: E402

TINY = {"kind": "fourier-voronoi-2d", "seed": 1, "particles": 10, "contour_points": 16,
        "imc": {"max_steps": 0}, "outputs": ["grains"]}


def parse_ts(s):
    """RFC 3339 with milliseconds (the store's) -> seconds."""
    t = time.strptime(s[:19], "%Y-%m-%dT%H:%M:%S")
    return time.mktime(t) + float("0" + s[19:-1])


def template(env, url, daemon_args):
    """One daemon submits and finishes the template job, then stops; its id."""
    d = gpd.Daemon(env.binary, env.db, workers=1, extra=daemon_args, tag="t")
    d.db_arg = url
    d.start()
    jid = d.submit(TINY)
    assert d.wait(jid)["status"] == "succeeded"
    assert d.stop() == 0, d.read_log()
    return jid


def fill_sqlite(path, jid, n, kind):
    con = sqlite3.connect(path)
    con.execute("WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c WHERE x < ?) "
                "INSERT INTO jobs(id, kind, spec, status, created_at, brief) "
                "SELECT lower(hex(randomblob(16))), ?, spec, 'queued', created_at, brief "
                "FROM jobs, c WHERE id = ?", (n, kind, jid))
    con.commit()
    con.close()


def fill_pg(pg, db, jid, n, kind):
    pg.psql("INSERT INTO jobs(id, kind, spec, status, created_at, brief) "
            "SELECT md5(random()::text || g::text), :'kind', spec, 'queued', created_at, brief "
            "FROM jobs, generate_series(1, :'n'::int) g WHERE id = :'jid';\n",
            db, {"n": n, "jid": jid, "kind": kind})


def spans(rows, expect):
    """rows of (status, started_at, finished_at, written): claimed/s, done/s, jobs not ending
    as expected, results not written once (None where unknown)."""
    n = len(rows)
    starts = sorted(parse_ts(r[1]) for r in rows)
    ends = [parse_ts(r[2]) for r in rows]
    bad = sum(1 for r in rows if r[0] != expect)
    want = "1" if expect == "succeeded" else "0"
    dup = None if rows[0][3] is None else sum(1 for r in rows if str(r[3]) != want)
    claim = (n - 1) / max(starts[-1] - starts[0], 1e-6)
    done = n / max(max(ends) - starts[0], 1e-6)
    return claim, done, bad, dup


def drain(env, urls, args, jobs):
    """Starts one daemon per URL, waits until the queue is empty and nothing runs; stops them."""
    ds = []
    for i, url in enumerate(urls):
        d = gpd.Daemon(env.binary, env.db, workers=args.workers, tag="q%d" % i,
                       extra=["--log-level", "warn"])
        d.db_arg = url
        ds.append(d)
    for d in ds:
        d.start()
    deadline = time.time() + 600
    while True:
        h = ds[0].json("GET", "/v1/health")[2]["jobs"]
        if h["queued"] == 0 and h["running"] == 0:
            break
        assert time.time() < deadline, h
        time.sleep(0.1)
    for d in ds:
        assert d.stop() == 0, d.read_log()


NOOP_KIND = "bench-noop"  # a kind no build has: claimed, then failed at once


def queue_row(env, backend, ndaemons, job, args):
    kind = TINY["kind"] if job == "2D tiny" else NOOP_KIND
    expect = "succeeded" if job == "2D tiny" else "failed"
    if backend == "sqlite":
        path = os.path.join(env.dir, "q%s.db" % kind)
        jid = template(env, path, [])
        fill_sqlite(path, jid, args.jobs, kind)
        drain(env, [path], args, args.jobs)
        con = sqlite3.connect(path)
        rows = [r + (None,) for r in con.execute(
            "SELECT status, started_at, finished_at FROM jobs WHERE id != ?", (jid,))]
        con.close()
    else:
        pg = gpd.pg_server()
        db = pg.create_db("bq")
        url = pg.url(db)
        jid = template(env, url, [])
        fill_pg(pg, db, jid, args.jobs, kind)
        drain(env, [url] * ndaemons, args, args.jobs)
        out = pg.psql("SELECT status, started_at, finished_at, results_written FROM jobs "
                      "WHERE id != :'jid';\n", db, {"jid": jid})
        rows = [tuple(line.split("|")) for line in out.splitlines() if line]
    return spans(rows, expect)


def poll_row(env, backend, args):
    """wrk against GET /v1/jobs/{id} of a succeeded job: requests/s, p99 ms, errors."""
    if backend == "sqlite":
        url = os.path.join(env.dir, "p.db")
    else:
        url = gpd.pg_server().url(gpd.pg_server().create_db("bp"))
    d = gpd.Daemon(env.binary, env.db, workers=1, tag="p", extra=["--log-level", "warn"])
    d.db_arg = url
    d.start()
    try:
        jid = d.submit(TINY)
        assert d.wait(jid)["status"] == "succeeded"
        lua = os.path.join(here, "load", "report.lua")
        r = subprocess.run(["wrk", "-t2", "-c%d" % args.connections, "-d%ds" % args.poll_seconds,
                            "--timeout", "10s", "-s", lua, "%s/v1/jobs/%s" % (d.url, jid)],
                           capture_output=True, text=True, timeout=args.poll_seconds + 60)
        line = [x for x in r.stdout.splitlines() if x.startswith("RESULT")][0]
        kv = dict(x.split("=") for x in line.split()[1:])
        rps = float(kv["requests"]) / (float(kv["duration_us"]) / 1e6)
        return rps, float(kv["p99"]) / 1e3, int(kv["errors"]) + int(kv["non2xx"])
    finally:
        assert d.stop() == 0, d.read_log()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--jobs", type=int, default=400)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--poll-seconds", type=int, default=5)
    ap.add_argument("--connections", type=int, default=50)
    args = ap.parse_args()
    env = gpd.Env(args.binary)
    gpd._pg = gpd.PgServer(durable=True).start()
    try:
        load = os.getloadavg()
        print("bench_queue: %d trivially small jobs, %d workers per daemon, %d cores, load %.2f; "
              "PostgreSQL %s (fsync on)" % (args.jobs, args.workers, os.cpu_count(), load[0],
                                             os.path.basename(os.path.dirname(gpd.pg_bindir()))))
        print("%-8s %-10s %7s %10s %9s %8s %11s %9s %8s" % (
            "job", "backend", "daemons", "claimed/s", "done/s", "wrong", "written!=1",
            "polls/s", "p99 ms"))
        for job in ("2D tiny", "no-op"):
            for backend, nd in (("sqlite", 1), ("postgresql", 1), ("postgresql", 2),
                                ("postgresql", 4)):
                claim, done, bad, dup = queue_row(env, backend, nd, job, args)
                poll = ""
                if nd == 1 and job == "2D tiny":
                    rps, p99, errs = poll_row(env, backend, args)
                    poll = "%9.0f %8.2f" % (rps, p99) + ("  (%d errors)" % errs if errs else "")
                print("%-8s %-10s %7d %10.1f %9.1f %8d %11s %s" % (
                    job, backend, nd, claim, done, bad, "-" if dup is None else dup, poll),
                    flush=True)
        print("wrong: jobs not ending as they must (2D tiny: succeeded; no-op: failed "
              "not_implemented); written!=1: results written other than once (no-op: other "
              "than 0)")
    finally:
        env.close()
        if gpd._pg is not None:
            gpd._pg.stop()


if __name__ == "__main__":
    main()
