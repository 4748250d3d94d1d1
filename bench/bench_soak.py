#!/usr/bin/env python3
"""bench_soak.py -- grainpackd run for a long time: does it stay small, fast and correct?

    python3 bench/bench_soak.py build/server/grainpackd [--minutes 60] [--workers 2]
                                [--retain-days 0.002] [--purge-share 0.3] [--inflight 4]

Starts one daemon on a free port with a temporary database and a short retention
(--retain-days is a real number of days: 0.002 is about 3 minutes), then for --minutes keeps
--inflight small jobs in the queue -- two 2D Fourier-Voronoi specimens (20 to 60 grains, ODEC
discs) for one 3D packing (a 6 mm box of 1-2 mm spheres) -- and for each one polls it until it
finishes, downloads its result and one export (a format at random), and then purges a share of
them itself (DELETE ?purge=1, --purge-share) and leaves the rest to the retention sweep. It also
scrapes GET /metrics every second, as Prometheus would. Every minute it prints one row:

    minute, jobs done in that minute (and in all; a 3D job may end "infeasible", the core's
    answer for a seed whose few spheres cannot reach the porosity, which is not counted as a
    failure), jobs purged by DELETE and by the retention sweep so far, jobs in the database
    (grainpack_jobs), the database on disk (file + WAL, MB) and its WAL alone, the daemon's RSS
    (MB), the p99 latency of the status polls in that minute (ms), and the jobs lost (a job
    answered 404 before anyone should have removed it) or stuck (not finished within --stuck-s
    seconds of its submit).

In a healthy run the database and the RSS level off once the retention has begun to purge
(after --retain-days), the p99 stays flat, and lost and stuck stay 0. The exit status is 1 when
a job was lost or stuck, or a download or a purge failed. Linux only (/proc). Python standard
library only; reuses bench_export.py's helpers.
"""
import argparse
import json
import os
import random
import shutil
import sys
import tempfile
import time
import urllib.error
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_export import FORMATS, call, download, proc_status, start, stop, submit  # noqa: E402

FINAL = ("succeeded", "failed", "cancelled")
CORE_ANSWERS = ("infeasible", "not_converged")


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


def purge(base, jid):
    """DELETE ?purge=1: the status (204 when purged; no body)."""
    req = urllib.request.Request(base + "/v1/jobs/%s?purge=1" % jid, method="DELETE")
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            r.read()
            return r.status
    except urllib.error.HTTPError as e:
        e.read()
        return e.code


def timed_poll(base, jid):
    """GET /v1/jobs/{id}: (status, job or None, seconds)."""
    t0 = time.perf_counter()
    try:
        with urllib.request.urlopen(base + "/v1/jobs/" + jid, timeout=60) as r:
            body = r.read()
            st = r.status
    except urllib.error.HTTPError as e:
        body = e.read()
        st = e.code
    dt = time.perf_counter() - t0
    return st, (json.loads(body) if st == 200 else None), dt


def scrape(base):
    """GET /metrics: {name{labels}: value}."""
    with urllib.request.urlopen(base + "/metrics", timeout=30) as r:
        text = r.read().decode()
    out = {}
    for line in text.splitlines():
        if line and not line.startswith("#"):
            k, _, v = line.rpartition(" ")
            out[k] = float(v)
    return out


def file_mb(path):
    return os.path.getsize(path) / 1e6 if os.path.exists(path) else 0.0


def p99(xs):
    if not xs:
        return float("nan")
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(0.99 * (len(xs) - 1) + 0.5))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--minutes", type=float, default=60)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--retain-days", type=float, default=0.002)
    ap.add_argument("--purge-share", type=float, default=0.3)
    ap.add_argument("--inflight", type=int, default=4, help="jobs kept submitted at once")
    ap.add_argument("--stuck-s", type=float, default=300,
                    help="a job not finished by then is stuck")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--keep", action="store_true", help="keep the temporary directory")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    tmp = tempfile.mkdtemp(prefix="gpd-soak-")
    db = os.path.join(tmp, "soak.db")
    retain_s = a.retain_days * 86400
    # bench_export.start passes no extra flags: the retention comes by the environment
    os.environ["GRAINPACK_RETAIN_DAYS"] = repr(a.retain_days)
    proc, base = start(a.binary, db, a.workers)
    print("grainpackd %s, db %s, %d workers, retention %g days (%.0f s), %.0f %% purged by "
          "DELETE, %d jobs in flight" % (base, db, a.workers, a.retain_days, retain_s,
                                         100 * a.purge_share, a.inflight), flush=True)
    print("%6s %6s %6s %7s %8s %6s %7s %7s %7s %7s %11s" % (
        "minute", "done", "total", "purged", "expired", "in db", "db MB", "WAL MB", "RSS MB",
        "p99 ms", "lost/stuck"), flush=True)
    inflight = {}   # id -> (submitted at, kind)
    retained = {}   # id -> finished at (wall clock), left to the retention sweep
    done_total = purged = expired = lost = stuck = failures = infeasible = 0
    done_min, lat = 0, []
    t_start = time.time()
    t_end = t_start + 60 * a.minutes
    next_row = t_start + 60
    next_scrape = t_start
    minute = 0
    metrics = {}
    try:
        while True:
            now = time.time()
            if now >= next_scrape:
                try:
                    metrics = scrape(base)
                except (OSError, ValueError) as e:
                    failures += 1
                    print("  /metrics failed: %r" % e, flush=True)
                next_scrape = now + 1
            if now >= next_row or now >= t_end:
                minute += 1
                # the jobs left to retention: gone too early = lost; gone later = expired
                for jid, fin in list(retained.items()):
                    st, _, _ = timed_poll(base, jid)
                    if st == 404:
                        del retained[jid]
                        if time.time() - fin < retain_s - 5:
                            lost += 1
                            print("  job %s gone %.0f s after it finished (retention %.0f s)"
                                  % (jid, time.time() - fin, retain_s), flush=True)
                        else:
                            expired += 1
                in_db = sum(v for k, v in metrics.items() if k.startswith("grainpack_jobs{"))
                rss = proc_status(proc.pid)["VmRSS"] / 1024.0
                health, _ = call(base + "/v1/health")
                if health != 200:
                    failures += 1
                    print("  /v1/health: %s" % health, flush=True)
                print("%6d %6d %6d %7d %8d %6d %7.1f %7.1f %7.1f %7.1f %7d/%-3d" % (
                    minute, done_min, done_total, purged, expired, in_db,
                    file_mb(db) + file_mb(db + "-wal"), file_mb(db + "-wal"), rss,
                    1e3 * p99(lat), lost, stuck), flush=True)
                done_min, lat = 0, []
                next_row += 60
                if now >= t_end:
                    break
            while len(inflight) < a.inflight:
                is3d = rng.random() < 1 / 3
                jid = submit(base, spec_3d(rng) if is3d else spec_2d(rng))
                inflight[jid] = (time.time(), 3 if is3d else 2)
            for jid, (t_sub, dim) in list(inflight.items()):
                st, j, dt = timed_poll(base, jid)
                lat.append(dt)
                if st != 200:
                    lost += 1
                    del inflight[jid]
                    print("  job %s: %d while it was in flight" % (jid, st), flush=True)
                    continue
                if j["status"] not in FINAL:
                    if time.time() - t_sub > a.stuck_s:
                        stuck += 1
                        del inflight[jid]
                        print("  job %s stuck %s after %.0f s" % (jid, j["status"], a.stuck_s),
                              flush=True)
                    continue
                del inflight[jid]
                done_total += 1
                done_min += 1
                if j["status"] != "succeeded":
                    # a few dozen spheres in a 6 mm box: some seeds cannot reach the porosity
                    # (the core says so); that is the job's answer, not the daemon's failure
                    if (j["error"] or {}).get("code") in CORE_ANSWERS:
                        infeasible += 1
                    else:
                        failures += 1
                        print("  job %s %s: %s" % (jid, j["status"], j["error"]), flush=True)
                else:
                    for path in ("/result", "/export?format=" + rng.choice(FORMATS[dim])):
                        try:
                            code, _ = download(base + "/v1/jobs/" + jid + path)
                        except (OSError, urllib.error.HTTPError) as e:
                            code = repr(e)
                        if code != 200:
                            failures += 1
                            print("  GET %s%s: %s" % (jid, path, code), flush=True)
                if rng.random() < a.purge_share:
                    code = purge(base, jid)
                    if code == 204:
                        purged += 1
                    elif code == 404 and retain_s < 60:
                        expired += 1  # the sweep was first (a very short retention)
                    else:
                        failures += 1
                        print("  purge %s: %s" % (jid, code), flush=True)
                else:
                    retained[jid] = time.time()
            time.sleep(0.05)
    finally:
        stop(proc)
        if not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            print("kept " + tmp)
    print("%d jobs done in %.1f min (%d of them failed as infeasible: a 3D seed whose few "
          "spheres cannot reach the porosity); %d purged by DELETE, %d by the retention sweep; "
          "lost %d, stuck %d, other failures %d" % (
              done_total, (time.time() - t_start) / 60, infeasible, purged, expired, lost, stuck,
              failures))
    sys.exit(1 if lost or stuck or failures else 0)


if __name__ == "__main__":
    main()
