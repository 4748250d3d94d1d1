#!/usr/bin/env python3
"""bench_soak.py -- grainpackd run for a long time under a mixed load: does it stay small, fast
and correct, and does it ride out a database restart?

    python3 bench/bench_soak.py build/server/grainpackd [--db sqlite|postgresql] [--minutes 60]
        [--workers 2] [--retain-days 0.002] [--purge-share 0.3] [--inflight 4]
        [--restart-at 0.5] [--outage-s 20] [--analysis-every 10] [--slow-clients 200]
        [--slow-readers 4]

Starts one daemon on a free port with a temporary database -- an SQLite file, or a PostgreSQL
server of its own (initdb + pg_ctl in a temporary directory) -- and a short retention
(--retain-days is a real number of days: 0.002 is about 3 minutes). Then for --minutes:

  jobs          --inflight small jobs kept in the queue -- two 2D Fourier-Voronoi specimens (20 to
                60 grains, ODEC discs) for one 3D packing (a 6 mm box of 1-2 mm spheres) -- each
                polled until it finishes, its result and one export (a format at random)
                downloaded, then purged by DELETE ?purge=1 (--purge-share) or left to the
                retention sweep;
  analyses      a POST /v1/shapes/analyze of 40 outlines every --analysis-every seconds, one in
                three abandoned 0.3 s after it is sent (the daemon must drop it unrun);
  slow clients  --slow-clients connections from 127.0.0.2-11 trickling a header line every 5 s
                (the daemon closes them at --header-timeout; they come back), and --slow-readers
                threads downloading exports of finished jobs at 16 KB/s;
  health        GET /v1/health twice a second on a new connection; GET /metrics every second;
  restart       PostgreSQL only: at --restart-at of the run the database server is stopped
                (pg_ctl -m fast), left down --outage-s seconds, and started again.

A client does what the contract asks of one: a 503 (busy, or the database unavailable) is tried
again after its Retry-After. Every minute one row:

    minute; jobs done in that minute and in all; jobs purged by DELETE and by the retention sweep
    so far; jobs in the database; the database's size (MB, grainpack_database_bytes); the
    daemon's RSS (MB); p99 of the status polls and of /v1/health in that minute (ms); 503s
    answered in that minute; analyses answered / abandoned so far; slow connections open; and
    the jobs lost (answered 404 before anyone should have removed it) or stuck (not finished
    within --stuck-s of its submit), and other failures (a job failed for any reason but the
    core's own answer, a download, purge or analysis that went wrong).

The end prints RSS and the p99s of the first and last quarter side by side (after the first
five minutes). The exit status is 1 when a job was lost or stuck or anything failed. Linux only
(/proc). Python standard library only; reuses bench_export.py's and the integration tests'
helpers.
"""
import argparse
import json
import math
import os
import random
import socket
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "integration"))
from bench_export import FORMATS, proc_status  # noqa: E402
import gpd  # noqa: E402

FINAL = ("succeeded", "failed", "cancelled")
CORE_ANSWERS = ("infeasible", "not_converged")
ANALYZE = "/v1/shapes/analyze"
RETRY_FOR_S = 300  # a 503 is retried this long at most


def spec_2d(rng):
    return {"kind": "fourier-voronoi-2d", "seed": rng.randrange(1 << 30),
            "particles": rng.randrange(20, 61), "contour_points": rng.choice([16, 32]),
            "size": {"cov": 0.5},
            "imc": {"error": "E3", "threshold": 0.05, "max_steps": 20000, "init": "halton"},
            "outputs": ["grains", "odec"]}


def spec_3d(rng):
    return {"kind": "spheres-3d", "seed": rng.randrange(1 << 30), "box": [0.006, 0.006, 0.006],
            "sieve": [[1, 0], [2, 100]], "sieve_units": "mm", "porosity": 0.52,
            "outputs": ["spheres"]}


def outlines(rng, n, points=100):
    """n star-shaped grain outlines [[x, y], ...] with a small random spectrum"""
    out = []
    for _ in range(n):
        amp = [(k, rng.uniform(0, 0.12 / k), rng.uniform(0, 2 * math.pi)) for k in range(2, 9)]
        ring = []
        for i in range(points):
            t = 2 * math.pi * i / points
            r = 1 + sum(a * math.cos(k * t + p) for k, a, p in amp)
            ring.append([round(r * math.cos(t), 6), round(r * math.sin(t), 6)])
        out.append(ring)
    return out


def p99(xs):
    if not xs:
        return float("nan")
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(0.99 * (len(xs) - 1) + 0.5))]


class Tally:
    """Counters and latencies shared by the threads; the per-minute ones are reset by take()."""

    def __init__(self):
        self.mu = threading.Lock()
        self.total = {}
        self.minute = {}
        self.lat = {"poll": [], "health": []}

    def add(self, key, n=1, per_minute=False):
        with self.mu:
            self.total[key] = self.total.get(key, 0) + n
            if per_minute:
                self.minute[key] = self.minute.get(key, 0) + n

    def latency(self, key, s):
        with self.mu:
            self.lat[key].append(s)

    def failure(self, what):
        self.add("failures")
        print("  " + what, flush=True)

    def set(self, key, value):
        with self.mu:
            self.total[key] = value

    def get(self, key):
        with self.mu:
            return self.total.get(key, 0)

    def take(self):
        with self.mu:
            m, lat = self.minute, self.lat
            self.minute, self.lat = {}, {"poll": [], "health": []}
        return m, lat


class Client:
    """HTTP with the contract's retry rule: a 503 again after its Retry-After (at most 2 s),
    for RETRY_FOR_S at most."""

    def __init__(self, base, tally, stop):
        self.base = base
        self.tally = tally
        self.stop = stop

    def once(self, method, path, body=None, timeout=120):
        data = json.dumps(body).encode() if body is not None else None
        req = urllib.request.Request(self.base + path, data=data, method=method,
                                     headers={"Content-Type": "application/json"} if data else {})
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                return r.status, r.headers, r.read()
        except urllib.error.HTTPError as e:
            return e.code, e.headers, e.read()

    def call(self, method, path, body=None, retry=True, timeout=120):
        """(status, headers, bytes); status None after a connection error (counted a failure)"""
        give_up = time.time() + RETRY_FOR_S
        while True:
            try:
                st, hd, b = self.once(method, path, body, timeout)
            except OSError as e:
                self.tally.failure("%s %s: %r" % (method, path, e))
                return None, None, b""
            if st != 503:
                return st, hd, b
            self.tally.add("503", per_minute=True)
            if not retry or time.time() > give_up or self.stop.is_set():
                return st, hd, b
            try:
                wait = float(hd.get("Retry-After") or 1)
            except ValueError:
                wait = 1
            time.sleep(min(2.0, max(0.2, wait)))

    def json(self, method, path, body=None, retry=True):
        st, _, b = self.call(method, path, body, retry)
        try:
            return st, json.loads(b) if b else None
        except ValueError:
            return st, None


# ------------------------------------------------------------------ the threads

def health_loop(c, stop):
    while not stop.is_set():
        t0 = time.perf_counter()
        try:
            st, _, _ = c.once("GET", "/v1/health", timeout=30)
        except OSError as e:
            st = repr(e)
        c.tally.latency("health", time.perf_counter() - t0)
        if st != 200:
            c.tally.add("health_not_ok", per_minute=True)
            c.tally.add("health_%s" % st)
        stop.wait(0.5)


def metrics_loop(c, stop, shared):
    while not stop.is_set():
        st, _, b = c.call("GET", "/metrics", retry=False, timeout=30)
        if st == 200:
            out = {}
            for line in b.decode().splitlines():
                if line and not line.startswith("#"):
                    k, _, v = line.rpartition(" ")
                    out[k] = float(v)
            shared["metrics"] = out
        elif st is not None:
            c.tally.failure("/metrics: %s" % st)
        stop.wait(1.0)


def analyses_loop(c, stop, every, seed):
    rng = random.Random(seed)
    port = int(c.base.rsplit(":", 1)[1])
    while not stop.wait(every):
        n = 40
        body = {"outlines": outlines(rng, n)}
        if rng.random() < 1 / 3:
            raw = json.dumps(body).encode()
            try:
                s = socket.create_connection(("127.0.0.1", port), timeout=30)
                s.sendall(b"POST %s HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: "
                          b"application/json\r\nContent-Length: %d\r\n\r\n"
                          % (ANALYZE.encode(), len(raw)) + raw)
                time.sleep(0.3)
                s.close()
                c.tally.add("abandoned")
            except OSError as e:
                c.tally.failure("abandoned analysis: %r" % e)
            continue
        st, j = c.json("POST", ANALYZE, body)
        if st == 200 and j and j.get("analysed") == n:
            c.tally.add("analysed")
        elif st is not None:
            c.tally.failure("analysis: %s %s" % (st, str(j)[:200]))


def slow_loop(port, n, stop, tally):
    """n connections trickling header lines from 127.0.0.2-11; reopened when closed"""
    socks = [None] * n
    k = 0
    while not stop.is_set():
        k += 1
        open_ = 0
        for i in range(n):
            s = socks[i]
            if s is not None:
                try:
                    s.send(b"X-Slow-%d: a\r\n" % k)
                    open_ += 1
                    continue
                except OSError:
                    s.close()
                    socks[i] = None
                    tally.add("slow_closed")
            try:
                s = socket.socket()
                s.bind(("127.0.0.%d" % (2 + i % 10), 0))
                s.settimeout(5)
                s.connect(("127.0.0.1", port))
                s.setblocking(False)
                s.send(b"GET /v1/health HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow-0: a\r\n")
                socks[i] = s
                open_ += 1
            except OSError:
                s.close()
        tally.set("slow_open_now", open_)
        stop.wait(5)
    for s in socks:
        if s is not None:
            s.close()


def slow_reader_loop(c, stop, shared, seed):
    """downloads exports of finished jobs at 16 KB/s"""
    rng = random.Random(seed)
    while not stop.wait(1.0):
        done = shared["succeeded"]
        if not done:
            continue
        jid, dim = rng.choice(done[-50:])
        path = "/v1/jobs/%s/export?format=%s" % (jid, rng.choice(FORMATS[dim]))
        try:
            with urllib.request.urlopen(c.base + path, timeout=120) as r:
                while not stop.is_set():
                    if not r.read(4096):
                        break
                    time.sleep(0.25)
            c.tally.add("slow_reads")
        except urllib.error.HTTPError as e:
            e.read()
            if e.code == 503:
                c.tally.add("503", per_minute=True)
            elif e.code != 404:  # purged meanwhile: fine
                c.tally.failure("slow read %s: %s" % (path, e.code))
        except OSError as e:
            c.tally.failure("slow read %s: %r" % (path, e))


# ------------------------------------------------------------------ the database

def restart_pg(pg, outage_s, tally):
    t0 = time.time()
    pg.halt()
    print("  PostgreSQL stopped (pg_ctl -m fast, %.1f s); down for %g s"
          % (time.time() - t0, outage_s), flush=True)
    time.sleep(outage_s)
    try:
        pg.resume()
        print("  PostgreSQL started again", flush=True)
    except RuntimeError as e:
        tally.failure("PostgreSQL did not start again: %s" % e)


# ------------------------------------------------------------------ the jobs

class Jobs:
    """The jobs' side of the soak: submit, poll, download, purge, check the retained."""

    def __init__(self, c, a, rng, shared):
        self.c, self.a, self.rng, self.shared = c, a, rng, shared
        self.t = c.tally
        self.inflight = {}   # id -> (submitted at, dimension)
        self.retained = {}   # id -> finished at, left to the retention sweep
        self.retain_s = a.retain_days * 86400

    def fill(self):
        while len(self.inflight) < self.a.inflight:
            is3d = self.rng.random() < 1 / 3
            st, j = self.c.json("POST", "/v1/jobs", spec_3d(self.rng) if is3d
                                else spec_2d(self.rng))
            if st != 201:
                self.t.failure("submit: %s %s" % (st, j))
                return
            self.inflight[j["id"]] = (time.time(), 3 if is3d else 2)

    def poll(self):
        for jid, (t_sub, dim) in list(self.inflight.items()):
            t0 = time.perf_counter()
            st, j = self.c.json("GET", "/v1/jobs/" + jid, retry=False)
            self.t.latency("poll", time.perf_counter() - t0)
            if st == 503 or st is None:
                continue  # the database is away: later
            if st != 200:
                self.t.add("lost")
                del self.inflight[jid]
                print("  job %s: %d while it was in flight" % (jid, st), flush=True)
                continue
            if j["status"] not in FINAL:
                if time.time() - t_sub > self.a.stuck_s:
                    self.t.add("stuck")
                    del self.inflight[jid]
                    print("  job %s stuck %s after %.0f s" % (jid, j["status"], self.a.stuck_s),
                          flush=True)
                continue
            del self.inflight[jid]
            self.finished(jid, dim, j)

    def finished(self, jid, dim, j):
        self.t.add("done", per_minute=True)
        if j["status"] != "succeeded":
            # a few dozen spheres in a 6 mm box: some seeds cannot reach the porosity (the
            # core says so); that is the job's answer, not the daemon's failure
            if (j["error"] or {}).get("code") in CORE_ANSWERS:
                self.t.add("infeasible")
            else:
                self.t.failure("job %s %s: %s" % (jid, j["status"], j["error"]))
        else:
            self.shared["succeeded"].append((jid, dim))
            del self.shared["succeeded"][:-200]
            for path in ("/result", "/export?format=" + self.rng.choice(FORMATS[dim])):
                st, _, _ = self.c.call("GET", "/v1/jobs/" + jid + path)
                if st != 200 and st is not None:
                    self.t.failure("GET %s%s: %s" % (jid, path, st))
        if self.rng.random() < self.a.purge_share:
            st, _, _ = self.c.call("DELETE", "/v1/jobs/%s?purge=1" % jid)
            if st == 204:
                self.t.add("purged")
            elif st == 404 and self.retain_s < 60:
                self.t.add("expired")  # the sweep was first (a very short retention)
            elif st is not None:
                self.t.failure("purge %s: %s" % (jid, st))
        else:
            self.retained[jid] = time.time()

    def check_retained(self):
        """the jobs left to retention: gone too early = lost; gone later = expired"""
        for jid, fin in list(self.retained.items()):
            st, _ = self.c.json("GET", "/v1/jobs/" + jid)
            if st == 404:
                del self.retained[jid]
                if time.time() - fin < self.retain_s - 5:
                    self.t.add("lost")
                    print("  job %s gone %.0f s after it finished (retention %.0f s)"
                          % (jid, time.time() - fin, self.retain_s), flush=True)
                else:
                    self.t.add("expired")


# ------------------------------------------------------------------ main

HEAD = ("minute", "done", "total", "purged", "expired", "in db", "db MB", "RSS MB", "poll p99",
        "health p99", "503s", "analyses", "slow", "lost/stuck/fail")


def row(minute, t, m, lat, shared, rss):
    metrics = shared["metrics"]
    in_db = sum(v for k, v in metrics.items() if k.startswith("grainpack_jobs{"))
    dbmb = metrics.get("grainpack_database_bytes", 0) / 1e6
    return "%6d %5d %6d %7d %8d %6d %7.1f %7.1f %9.1f %11.1f %5d %5d/%-4d %5d %7d/%d/%d" % (
        minute, m.get("done", 0), t.get("done"), t.get("purged"), t.get("expired"), in_db, dbmb,
        rss, 1e3 * p99(lat["poll"]), 1e3 * p99(lat["health"]), m.get("503", 0),
        t.get("analysed"), t.get("abandoned"), t.get("slow_open_now"), t.get("lost"),
        t.get("stuck"), t.get("failures"))


def quarters(rows):
    """(RSS, poll p99, health p99) of the first and last quarter after minute 5"""
    body = [r for r in rows if r[0] > 5] or rows
    q = max(1, len(body) // 4)

    def avg(rs, i):
        xs = [r[i] for r in rs if not math.isnan(r[i])]
        return sum(xs) / len(xs) if xs else float("nan")
    return [(avg(body[:q], i), avg(body[-q:], i)) for i in (1, 2, 3)]


def start_daemon(a, tmp):
    env = {"GRAINPACK_RETAIN_DAYS": repr(a.retain_days)}
    d = gpd.Daemon(a.binary, os.path.join(tmp, "soak.db"), a.workers,
                   extra=["--log-level", "warn"], env=env)
    pg = None
    if a.db == "postgresql":
        pg = gpd.PgServer().start()
        d.db_arg = pg.url(pg.create_db("soak"))
    return d.start(), pg


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--db", choices=("sqlite", "postgresql"), default="postgresql")
    ap.add_argument("--minutes", type=float, default=60)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--retain-days", type=float, default=0.002)
    ap.add_argument("--purge-share", type=float, default=0.3)
    ap.add_argument("--inflight", type=int, default=4, help="jobs kept submitted at once")
    ap.add_argument("--stuck-s", type=float, default=300,
                    help="a job not finished by then is stuck")
    ap.add_argument("--restart-at", type=float, default=0.5,
                    help="PostgreSQL: the share of the run at which the server is restarted")
    ap.add_argument("--outage-s", type=float, default=20)
    ap.add_argument("--analysis-every", type=float, default=10)
    ap.add_argument("--slow-clients", type=int, default=200)
    ap.add_argument("--slow-readers", type=int, default=4)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="gpd-soak-")
    d, pg = start_daemon(a, tmp)
    tally, stop = Tally(), threading.Event()
    c = Client(d.url, tally, stop)
    shared = {"metrics": {}, "succeeded": []}
    print("grainpackd %s on %s, %d workers, retention %g days (%.0f s), %.0f %% purged by "
          "DELETE, %d jobs in flight, %d slow clients, %d slow readers, an analysis every %g s%s"
          % (d.url, a.db, a.workers, a.retain_days, a.retain_days * 86400, 100 * a.purge_share,
             a.inflight, a.slow_clients, a.slow_readers, a.analysis_every,
             ", PostgreSQL down for %g s at minute %.1f" % (a.outage_s, a.restart_at * a.minutes)
             if pg else ""), flush=True)
    threads = [threading.Thread(target=health_loop, args=(c, stop)),
               threading.Thread(target=metrics_loop, args=(c, stop, shared)),
               threading.Thread(target=analyses_loop, args=(c, stop, a.analysis_every, a.seed)),
               threading.Thread(target=slow_loop, args=(d.port(), a.slow_clients, stop, tally))]
    threads += [threading.Thread(target=slow_reader_loop, args=(c, stop, shared, a.seed + k))
                for k in range(a.slow_readers)]
    for th in threads:
        th.start()
    print(" ".join(HEAD), flush=True)
    jobs = Jobs(c, a, random.Random(a.seed), shared)
    rows = []
    t_start = time.time()
    t_end = t_start + 60 * a.minutes
    t_restart = t_start + a.restart_at * 60 * a.minutes if pg else float("inf")
    restarter = None
    next_row, minute = t_start + 60, 0
    try:
        while True:
            now = time.time()
            if now >= t_restart:
                t_restart = float("inf")
                restarter = threading.Thread(target=restart_pg, args=(pg, a.outage_s, tally))
                restarter.start()
            if now >= next_row or now >= t_end:
                minute += 1
                jobs.check_retained()
                m, lat = tally.take()
                rss = proc_status(d.proc.pid)["VmRSS"] / 1024.0
                print(row(minute, tally, m, lat, shared, rss), flush=True)
                rows.append((minute, rss, 1e3 * p99(lat["poll"]), 1e3 * p99(lat["health"])))
                next_row += 60
                if now >= t_end:
                    break
            jobs.fill()
            jobs.poll()
            time.sleep(0.05)
    finally:
        stop.set()
        for th in threads:
            th.join(150)
        if restarter:
            restarter.join()
        rc = d.stop()
        if pg:
            pg.stop()
    (r0, r1), (p0, p1), (h0, h1) = quarters(rows)
    health = {k: v for k, v in tally.total.items() if k.startswith("health_")}
    print("%d jobs done in %.1f min (%d the core's answer infeasible); %d purged by DELETE, %d "
          "by the retention sweep; %d analyses answered, %d abandoned; %d slow readers' downloads; "
          "%d slow connections closed by the daemon; 503s %d; /v1/health not 200: %s; lost %d, "
          "stuck %d, other failures %d; daemon exit %s" % (
              tally.get("done"), (time.time() - t_start) / 60, tally.get("infeasible"),
              tally.get("purged"), tally.get("expired"), tally.get("analysed"),
              tally.get("abandoned"), tally.get("slow_reads"), tally.get("slow_closed"),
              tally.get("503"), health or "never", tally.get("lost"), tally.get("stuck"),
              tally.get("failures"), rc))
    print("first / last quarter: RSS %.1f / %.1f MB, poll p99 %.1f / %.1f ms, health p99 "
          "%.1f / %.1f ms" % (r0, r1, p0, p1, h0, h1))
    print("log: " + d.log_path)
    bad = tally.get("lost") or tally.get("stuck") or tally.get("failures") or rc != 0
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
