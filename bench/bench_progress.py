#!/usr/bin/env python3
"""bench_progress.py -- does a job's progress tell the truth? Fraction against elapsed time, ETA
against the time that was really left.

    python3 bench/bench_progress.py build/server/grainpackd [--jobs 3d,3d-tiled,2d-500,2d-10000]
                                    [--interval 0.1] [--samples FILE.json] [--report FILE.json]

Starts grainpackd on a free port with a temporary database and one worker, runs the jobs one
after the other (each alone on the worker), polls GET /v1/jobs/{id} every --interval seconds
while it runs and records (elapsed, phase, fraction, eta_s). The run of a job is the daemon's
own: from its started_at to its finished_at (same clock as this script's polls). It prints one
table per job: each phase with when the polls saw it and its fraction on entry and exit; the
largest |fraction - elapsed/total| over the polls (0 = a bar that moves with the clock); and at
25, 50 and 75 % of the run the reported eta_s next to the time really left (error = eta - left;
an ETA of 0 while work remains, or one that grows, shows here). Also counts the polls where the
fraction went down, and those without an ETA (null or 0) while more than 0.5 s was left.

Jobs (--jobs, comma-separated):
  3d        the api.md 3D example without tiling (0.5 m cube, porosity 0.38, every output)
  3d-tiled  the same sample, tiling [4, 4, 6], output spheres (about 233,000 spheres)
  3d-api    the api.md 3D example as it stands: tiling [4, 4, 4], spheres, contacts, fabric and
            stress (the issue's "tiling 100 %, eta 0.0 s"; not run unless asked for)
  2d-500    2D defaults, 500 grains, outputs grains and odec
  2d-10000  the same, 10,000 grains

Timing on a loaded machine is noisy: the figures are for comparing two builds on one machine.
Python standard library only; reuses bench_export.py's start/stop/submit helpers.
"""
import argparse
import datetime
import json
import os
import shutil
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_export import call, start, stop, submit  # noqa: E402

SPEC_3D = {"kind": "spheres-3d", "seed": 7, "box": [0.5, 0.5, 0.5],
           "sieve": [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]], "sieve_units": "mm",
           "porosity": 0.38,
           "material": {"density": 2600, "young": 15e6, "poisson": 0.5, "friction_deg": 18,
                        "damping": 0.2},
           "outputs": ["spheres", "contacts", "fabric", "stress"]}
SPEC_2D = {"kind": "fourier-voronoi-2d", "seed": 7, "outputs": ["grains", "odec"]}
JOBS = {
    "3d": ("3D api.md example, no tiling", SPEC_3D),
    "3d-tiled": ("3D tiling [4,4,6], spheres", dict(SPEC_3D, tiling=[4, 4, 6],
                                                     outputs=["spheres"])),
    "3d-api": ("3D api.md example, tiling [4,4,4], every output", dict(SPEC_3D, tiling=[4, 4, 4])),
    "2d-500": ("2D 500 grains, grains+odec", dict(SPEC_2D, particles=500)),
    "2d-10000": ("2D 10,000 grains, grains+odec", dict(SPEC_2D, particles=10000)),
}
FINAL = ("succeeded", "failed", "cancelled")


def rfc3339(s):
    """seconds since the epoch of the daemon's "2026-11-23T17:25:47.123Z" """
    return datetime.datetime.strptime(s, "%Y-%m-%dT%H:%M:%S.%fZ").replace(
        tzinfo=datetime.timezone.utc).timestamp()


def poll(base, jid, interval):
    """Polls job jid until it ends: (final job object, [(wall time, progress)] while running)."""
    samples = []
    while True:
        st, j = call(base + "/v1/jobs/" + jid)
        now = time.time()
        if st != 200:
            sys.exit("GET job: %s %s" % (st, j))
        if j["status"] == "running":
            samples.append((now, j["progress"]))
        if j["status"] in FINAL:
            return j, samples
        time.sleep(interval)


def phases(rows):
    """[(phase, first t, last t, fraction in, fraction out)] in the order seen"""
    out = []
    for t, p, f, _ in rows:
        if out and out[-1][0] == p:
            out[-1][2], out[-1][4] = t, f
        else:
            out.append([p, t, t, f, f])
    return out


def eta_at(rows, total, q):
    """the poll nearest to q of the run: (t, eta, time really left)"""
    t, _, _, eta = min(rows, key=lambda r: abs(r[0] - q * total))
    return t, eta, total - t


def report(label, job, samples):
    # the end: finished_at is stamped as the result's commit begins, and writing a large result
    # takes a second or more, so a later poll that still saw it running marks the end
    t0 = rfc3339(job["started_at"])
    t1 = max([rfc3339(job["finished_at"])] + [t for t, _ in samples])
    total = t1 - t0
    rows = [(t - t0, p["phase"], p["fraction"], p["eta_s"]) for t, p in samples if t0 <= t <= t1]
    print("\n%s: %s in %.2f s, %d polls" % (label, job["status"], total, len(rows)))
    if not rows or total <= 0:
        print("  (no poll saw it running)")
        return {}
    print("| phase | from s | to s | share of run | fraction in | fraction out |")
    print("|---|---:|---:|---:|---:|---:|")
    for p, a, b, fa, fb in phases(rows):
        print("| %s | %.2f | %.2f | %.0f %% | %.3f | %.3f |" % (p, a, b, 100 * (b - a) / total,
                                                                fa, fb))
    dev = max(rows, key=lambda r: abs(r[2] - r[0] / total))
    down = sum(1 for a, b in zip(rows, rows[1:]) if b[2] < a[2] - 1e-12)
    # no ETA (null or ~0) with work left, once the job has given one
    first = next((i for i, r in enumerate(rows) if r[3] is not None), len(rows))
    zero = sum(1 for r in rows[first:] if (r[3] is None or r[3] <= 0.05) and total - r[0] > 0.5)
    print("| **max abs(fraction - elapsed/total)** | %.3f | at %.2f s | in %s | fraction %.3f "
          "| elapsed/total %.3f |" % (abs(dev[2] - dev[0] / total), dev[0], dev[1], dev[2],
                                       dev[0] / total))
    out = {"total": total, "max_dev": abs(dev[2] - dev[0] / total), "down": down, "zero": zero}
    for q in (0.25, 0.5, 0.75):
        t, eta, left = eta_at(rows, total, q)
        err = "n/a (null)" if eta is None else "%+.2f s" % (eta - left)
        print("| ETA at %d %% of the run | %s | at %.2f s | eta_s %s | left %.2f s | |"
              % (100 * q, err, t, "null" if eta is None else "%.2f" % eta, left))
        out["eta%d" % (100 * q)] = None if eta is None else eta - left
    print("| fraction went down | %d polls | | no ETA (null or ~0) with > 0.5 s left | %d polls | |"
          % (down, zero))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--jobs", default="3d,3d-tiled,2d-500,2d-10000")
    ap.add_argument("--interval", type=float, default=0.1)
    ap.add_argument("--samples", help="write every poll here (JSON) for a closer look")
    ap.add_argument("--report", metavar="FILE", help="print the tables of a --samples file (of "
                    "another build, say) and run nothing")
    a = ap.parse_args()
    if a.report:
        with open(a.report) as f:
            for n, v in json.load(f).items():
                report(JOBS[n][0], v["job"], v["samples"])
        return
    names = [n for n in a.jobs.split(",") if n]
    for n in names:
        if n not in JOBS:
            sys.exit("unknown job %r; expected some of %s" % (n, ", ".join(JOBS)))
    tmp = tempfile.mkdtemp(prefix="bench-progress-")
    proc, base = start(os.path.abspath(a.binary), os.path.join(tmp, "bench.db"), 1)
    dump = {}
    try:
        for n in names:
            label, spec = JOBS[n]
            job, samples = poll(base, submit(base, spec), a.interval)
            dump[n] = {"job": job, "samples": samples, "summary": report(label, job, samples)}
    finally:
        stop(proc)
        shutil.rmtree(tmp, ignore_errors=True)
    if a.samples:
        with open(a.samples, "w") as f:
            json.dump(dump, f)


if __name__ == "__main__":
    main()
