#!/usr/bin/env python3
"""bench_lammps_relax.py -- the large relaxation in LAMMPS (issue #18), end to end.

    python3 bench/bench_lammps_relax.py build/server/grainpackd [--tiling 4,4,4] [--np 2]
        [--minutes 10] [--max-steps N] [--seed 7] [--keep DIR]

Starts grainpackd on a free port with a temporary database, builds the api.md 3D example (the
paper's sample: 0.5 m cube, the default Table-2 sieve, porosity 0.38, outputs spheres) tiled
4 x 4 x 4, downloads its lammps-relax export, unpacks it into an empty folder and runs
`mpirun -np 2 lmp -in relax.in` there, from the archive's files alone, for at most --minutes of
wall time (LAMMPS's own timer; -var timeout) or --max-steps. Prints one table: spheres, porosity,
coordination number and S_c before (grainpack's packing, as LAMMPS measures it, and grainpack's
own figures) and after the LAMMPS run, steps and seconds. When the run stops before S_c <= 1e-4,
the last line extrapolates the steps and time still needed from the decay of log S_c over the
second half of the run (a straight line in log S_c against steps), and says so.

Needs lmp (Debian lammps) and mpirun (openmpi-bin). As root, mpirun gets --allow-run-as-root.
Python standard library only; not part of `cmake --build build --target bench` (no C to build).
"""
import argparse
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_export import start, stop  # noqa: E402

SPEC = {"kind": "spheres-3d", "box": [0.5, 0.5, 0.5], "porosity": 0.38, "outputs": ["spheres"]}
THRESHOLD = 1e-4


def get(url, raw=False, body=None):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method="POST" if data else "GET",
                                 headers={"Content-Type": "application/json"} if data else {})
    with urllib.request.urlopen(req, timeout=600) as r:
        b = r.read()
        return (b, dict(r.headers)) if raw else json.loads(b)


def build(url, spec):
    """Submits spec and waits: (job id, summary, seconds)."""
    t0 = time.time()
    jid = get(url + "/v1/jobs", body=spec)["id"]
    while True:
        j = get(url + "/v1/jobs/" + jid)
        if j["status"] in ("succeeded", "failed", "cancelled"):
            break
        time.sleep(0.5)
    if j["status"] != "succeeded":
        sys.exit("the job %s: %s" % (j["status"], j["error"]))
    return jid, get(url + "/v1/jobs/%s/summary" % jid), time.time() - t0


def need(binary, package):
    path = shutil.which(binary)
    if not path:
        sys.exit("`%s` is not on PATH: install the Debian package %s" % (binary, package))
    return path


def run_lammps(folder, np_, minutes, max_steps, extra=()):
    """Runs relax.in in folder (extra: more -var pairs); (relax.json, wall seconds)."""
    cmd = [need("mpirun", "openmpi-bin"), "-np", str(np_)]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    cmd += [need("lmp", "lammps"), "-in", "relax.in", "-var", "timeout",
            "%d" % round(minutes * 60)]
    if max_steps:
        cmd += ["-var", "maxsteps", str(max_steps)]
    cmd += list(extra)
    print("running: (cd %s && %s)" % (folder, " ".join(cmd)), flush=True)
    t0 = time.time()
    p = subprocess.run(cmd, cwd=folder, capture_output=True, text=True,
                       env=dict(os.environ, OMP_NUM_THREADS="1"))
    wall = time.time() - t0
    if p.returncode != 0:
        sys.exit("LAMMPS failed (exit %d):\n%s" % (p.returncode, (p.stdout + p.stderr)[-4000:]))
    with open(os.path.join(folder, "relax.json")) as f:
        return json.load(f), wall


def thermo_rows(log_path):
    """(step, S_c) of the relaxation's thermo lines in log.lammps."""
    rows, cols = [], None
    with open(log_path) as f:
        for line in f:
            v = line.split()
            if v[:3] == ["Step", "Time", "v_Sc"]:
                cols = v
                continue
            if cols and len(v) == len(cols) and re.match(r"^\d+$", v[0]):
                rows.append((int(v[0]), float(v[2])))
            elif cols and v[:2] == ["Loop", "time"]:
                cols = None
    return rows


def extrapolate(rows, seconds):
    """Steps still needed to S_c <= 1e-4 from a least-squares line of log S_c over the second
    half of the run, and the time at this run's speed; None when S_c does not decay."""
    steps = rows[-1][0]
    tail = [(s, math.log(sc)) for s, sc in rows if s >= steps / 2 and sc > 0]
    if len(tail) < 3:
        return None
    n = len(tail)
    mx = sum(s for s, _ in tail) / n
    my = sum(y for _, y in tail) / n
    sxx = sum((s - mx) ** 2 for s, _ in tail)
    slope = sum((s - mx) * (y - my) for s, y in tail) / sxx
    if slope >= 0:
        return None
    at = my + slope * (steps - mx)  # the fitted log S_c at the last step
    more = (math.log(THRESHOLD) - at) / slope
    return more, more * seconds / steps, slope


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--tiling", default="4,4,4")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--np", type=int, default=2, dest="np_")
    ap.add_argument("--minutes", type=float, default=10)
    ap.add_argument("--max-steps", type=int, default=0)
    ap.add_argument("--keep", help="unpack and run in this folder (kept), not a temporary one")
    a = ap.parse_args()
    tiling = [int(x) for x in a.tiling.split(",")]
    tmp = tempfile.mkdtemp(prefix="gp-bench-relax-")
    proc, url = start(os.path.abspath(a.binary), os.path.join(tmp, "jobs.db"), 1)
    try:
        spec = dict(SPEC, seed=a.seed, tiling=tiling)
        jid, summ, t_job = build(url, spec)
        t0 = time.time()
        body, headers = get(url + "/v1/jobs/%s/export?format=lammps-relax" % jid, raw=True)
        t_export = time.time() - t0
    finally:
        stop(proc)
    run_dir = a.keep or os.path.join(tmp, "run")
    os.makedirs(run_dir, exist_ok=True)
    with tarfile.open(fileobj=io.BytesIO(body), mode="r:") as t:
        t.extractall(run_dir)
    folder = os.path.join(run_dir, "lammps-relax")
    rep, wall = run_lammps(folder, a.np_, a.minutes, a.max_steps)
    rows = thermo_rows(os.path.join(folder, "log.lammps"))
    st = summ["stats"]
    b, f = rep["before"], rep["after"]
    tl = "x".join(map(str, tiling))
    print()
    print("| %s tiling of the paper's sample (seed %d), mpirun -np %d lmp | before | after |"
          % (tl, a.seed, a.np_))
    print("|---|---|---|")
    print("| spheres (sample %d) | %d | %d |" % (st["sample_particles"], st["particles"],
                                                rep["spheres"]))
    print("| porosity, LAMMPS (grainpack) | %.6f (%.6f) | %.6f |"
          % (b["porosity"], st["porosity"]["achieved"], f["porosity"]))
    print("| coordination number, LAMMPS (grainpack) | %.4f (%.4f) | %.4f |"
          % (b["coordination_number"], st["coordination_number"], f["coordination_number"]))
    print("| S_c (Eq. 7; grainpack's sample %.2g) | %.3g | %.3g |"
          % (st["stability"], b["stability"], f["stability"]))
    print("| steps (dt %.4g s) | 0 | %d (%s) |"
          % (rep["dt"], rep["steps"], "S_c <= 1e-4" if rep["stable"] else "stopped by the cap"))
    print("| wall time | grainpack job %.1f s, export %.1f s (%.1f MB tar) | LAMMPS run %.1f s "
          "(mpirun total %.1f s), %.1f ms/step |"
          % (t_job, t_export, len(body) / 1e6, rep["seconds"], wall,
             1e3 * rep["seconds"] / max(rep["steps"], 1)))
    if not rep["stable"]:
        ex = extrapolate(rows, rep["seconds"]) if rows else None
        if ex:
            print("extrapolated: S_c falls by a factor 10 every %.0f steps over the second half; "
                  "1e-4 in about %.0f more steps, %.1f h more at this speed (an estimate: S_c "
                  "decays unevenly)" % (math.log(10) / -ex[2], ex[0], ex[1] / 3600))
        else:
            print("extrapolated: S_c did not decay over the second half of the run; no estimate")
    if not a.keep:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
