#!/usr/bin/env python3
"""bench_export.py -- export throughput and the daemon's memory while it serves a large export.

    python3 bench/bench_export.py build/server/grainpackd [--tiling 4,4,6] [--grains 10000]

Starts grainpackd on a free port with a temporary database, runs the 3D paper example (0.5 m
cube, the default Table-2 sieve, porosity 0.38; tiled 4x4x6, about 233,000 spheres) and a 2D
Fourier-Voronoi job with ODEC discs (10,000 grains by default; --grains 0 skips it), then
restarts the daemon on the same database (so that the heap the jobs freed, still resident,
cannot absorb a buffered download unseen), downloads every export format and GET /result of
each job once, and prints one table:

    format, bytes, seconds, MB/s (10^6 bytes/s), the daemon's VmRSS just before the request,
    its peak RSS during it (VmHWM, reset with `echo 5 > /proc/PID/clear_refs` first), and the
    difference.

A streamed export keeps the difference at a few MB whatever the size of the file. The client
(this script, urllib, 1 MiB reads) discards what it receives. Linux only (/proc). Python
standard library only; not part of `cmake --build build --target bench` (no C to build).
"""
import argparse
import json
import os
import re
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

SPEC_3D = {"kind": "spheres-3d", "box": [0.5, 0.5, 0.5], "porosity": 0.38,
           "outputs": ["spheres"]}
SPEC_2D = {"kind": "fourier-voronoi-2d", "size": {"cov": 0.5},
           "outputs": ["grains", "odec", "descriptors"]}
FORMATS = {3: ["lammps", "liggghts", "yade", "vtk", "csv"], 2: ["lammps", "yade", "vtk", "csv"]}


def start(binary, db, workers):
    log = open(db + ".log", "ab")
    p = subprocess.Popen([binary, "--listen", "127.0.0.1:0", "--db", db, "--workers",
                          str(workers), "--log-level", "warn"],
                         stdout=subprocess.PIPE, stderr=log)
    line = b""
    deadline = time.time() + 30
    while not line.endswith(b"\n"):
        if time.time() > deadline or p.poll() is not None:
            p.kill()
            sys.exit("grainpackd did not start; see " + db + ".log")
        r, _, _ = select.select([p.stdout], [], [], 1)
        if r:
            line += os.read(p.stdout.fileno(), 1)
    m = re.match(r"listening on (http://\S+)", line.decode())
    assert m, line
    return p, m.group(1)


def stop(proc):
    if proc.poll() is not None:
        return
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def call(url, method="GET", body=None):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method=method,
                                 headers={"Content-Type": "application/json"} if data else {})
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read() or b"null")


def download(url, each=None):
    """GET url, reading the body in 1 MB pieces without keeping it, each piece handed to
    each(piece) when given: (status, bytes)."""
    n = 0
    with urllib.request.urlopen(url, timeout=600) as r:
        status = r.status
        while True:
            b = r.read(1 << 20)
            if not b:
                break
            n += len(b)
            if each:
                each(b)
    return status, n


def submit(base, spec):
    st, j = call(base + "/v1/jobs", "POST", spec)
    if st != 201:
        sys.exit("submit failed: %s %s" % (st, j))
    return j["id"]


def wait(base, jid, what):
    t0 = time.time()
    while True:
        st, j = call(base + "/v1/jobs/" + jid)
        if j["status"] in ("succeeded", "failed", "cancelled"):
            print("  %s: %s in %.1f s" % (what, j["status"], time.time() - t0), flush=True)
            return j
        time.sleep(0.5)


def proc_status(pid):
    out = {}
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            k, _, v = line.partition(":")
            if k in ("VmRSS", "VmHWM", "RssAnon", "RssFile"):
                out[k] = int(v.split()[0])  # kB
    return out


def measure(pid, url):
    """Downloads url once; returns bytes, seconds and the daemon's memory (kB)."""
    with open("/proc/%d/clear_refs" % pid, "w") as f:
        f.write("5")  # VmHWM := VmRSS
    before = proc_status(pid)
    peak_anon = [before["RssAnon"]]
    done = threading.Event()

    def sample():
        while not done.is_set():
            try:
                peak_anon[0] = max(peak_anon[0], proc_status(pid)["RssAnon"])
            except OSError:
                return
            time.sleep(0.002)

    th = threading.Thread(target=sample)
    th.start()
    t0 = time.perf_counter()
    try:
        status, n = download(url)
    finally:
        dt = time.perf_counter() - t0
        done.set()
        th.join()
    after = proc_status(pid)
    assert status == 200, (url, status)
    return {"bytes": n, "s": dt, "rss0": before["VmRSS"], "peak": after["VmHWM"],
            "anon0": before["RssAnon"], "anon_peak": peak_anon[0]}


def job_args(doc):
    """The arguments bench_export and bench_svg share: the daemon, and the jobs to build."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--tiling", default="4,4,6", help="3D tiling (default 4,4,6: 233,280 spheres)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--grains", type=int, default=10000, help="2D grains (0: no 2D job)")
    ap.add_argument("--workers", type=int, default=2)
    return ap


def main():
    ap = job_args(__doc__)
    ap.add_argument("--no-restart", action="store_true",
                    help="measure in the daemon that ran the jobs (its freed heap stays resident)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary database")
    a = ap.parse_args()

    tmp = tempfile.mkdtemp(prefix="bench-export-")
    proc, base = start(os.path.abspath(a.binary), os.path.join(tmp, "bench.db"), a.workers)
    pid = proc.pid
    try:
        jobs = []
        tiling = [int(v) for v in a.tiling.split(",")]
        print("jobs (daemon pid %d, %d workers):" % (pid, a.workers), flush=True)
        j3 = submit(base, dict(SPEC_3D, seed=a.seed, tiling=tiling))
        j2 = submit(base, dict(SPEC_2D, seed=a.seed, particles=a.grains)) if a.grains else None
        job = wait(base, j3, "3D paper example, tiling %s" % a.tiling)
        if job["status"] != "succeeded":
            sys.exit("the 3D job did not succeed: %s" % job["error"])
        st, res = call(base + "/v1/jobs/%s/result" % j3)
        jobs.append((3, j3, "3D %d spheres" % len(res["spheres"])))
        del res
        if j2:
            job = wait(base, j2, "2D %d grains" % a.grains)
            if job["status"] != "succeeded":
                sys.exit("the 2D job did not succeed: %s" % job["error"])
            st, res = call(base + "/v1/jobs/%s/result" % j2)
            nd = sum(len(g["discs"]) for g in res["grains"])
            jobs.append((2, j2, "2D %d grains, %d discs" % (len(res["grains"]), nd)))
            del res
        if not a.no_restart:
            # A fresh daemon on the same database: the heap that the jobs freed stays resident
            # in the old process and could absorb a buffered download without any RSS growth.
            stop(proc)
            proc, base = start(os.path.abspath(a.binary), os.path.join(tmp, "bench.db"), 1)
            pid = proc.pid
            print("  restarted the daemon (pid %d, VmRSS %.1f MB) to measure on a fresh heap"
                  % (pid, proc_status(pid)["VmRSS"] / 1024), flush=True)
        time.sleep(1)  # let the workers settle

        rows = []
        for dim, jid, label in jobs:
            for f in FORMATS[dim] + ["result"]:
                url = base + ("/v1/jobs/%s/result" % jid if f == "result"
                              else "/v1/jobs/%s/export?format=%s" % (jid, f))
                m = measure(pid, url)
                rows.append((label, f, m))
                print("  %-28s %-8s %11d bytes %7.2f s" % (label, f, m["bytes"], m["s"]),
                      flush=True)

        print("\nexport downloads (grainpackd %s, 1 client; MB = 10^6 bytes; RSS in MB; "
              "peak = VmHWM during the request)\n" % os.path.basename(a.binary))
        print("| specimen | format | bytes | seconds | MB/s | RSS before | peak RSS during | "
              "delta | anon delta |")
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
        for label, f, m in rows:
            print("| %s | %s | %d | %.3f | %.1f | %.1f | %.1f | %+.2f | %+.2f |" % (
                label, f if f != "result" else "GET /result", m["bytes"], m["s"],
                m["bytes"] / 1e6 / m["s"], m["rss0"] / 1024, m["peak"] / 1024,
                (m["peak"] - m["rss0"]) / 1024, (m["anon_peak"] - m["anon0"]) / 1024))
        print("\nanon delta: the largest anonymous RSS (heap) sampled every 2 ms, minus before.")
    finally:
        stop(proc)
        if a.keep:
            print("database kept in", tmp)
        else:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
