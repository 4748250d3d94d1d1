#!/usr/bin/env python3
"""bench_peers.py -- grainpack's Dang & Meguid sample against YADE's, in one go (issue #16).

    python3 bench/bench_peers.py [build] [--seed 7] [--repeat 1] [--no-yade | --yade-log FILE]

Runs `<build>/bench/bench_spheres3d 1 SEED --sample` (grainpack's core, one thread: the paper's
0.5 m cube, Table 1 material, Table 2 sieve, porosity 0.38, gravity, until S_c <= 1e-4) and then
`yade -j1 -n -x bench/peers/yade_dang_meguid.py SEED` (the same sample the usual YADE way:
makeCloud with the mass-based PSD, triaxial compaction, friction lowered to the porosity, walls
stopped, until S_c <= 1e-4 measured as grainpack measures it), one after the other, --repeat
times each (the fastest run of each is kept), and prints one table: spheres, steps, seconds,
S_c, porosity and its error, PSD error by weight, and the speed ratio YADE / grainpack. The
load average is printed beside it: on a shared machine both times grow with it.

--yade-log FILE takes YADE's row from the stdout of an earlier `yade ... yade_dang_meguid.py`
run (its RESULT line) instead of running it again (YADE takes minutes; the table then says so).
Python standard library only; needs yade (Debian's) for the second row.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TARGET_POROSITY = 0.38


def run_grainpack(build, seed):
    exe = os.path.join(build, "bench", "bench_spheres3d")
    t0 = time.time()
    out = subprocess.run([exe, "1", str(seed), "--sample"], capture_output=True, text=True,
                         check=True).stdout
    wall = time.time() - t0
    rows = [l for l in out.splitlines() if l.startswith("| grainpack |")]
    if not rows:
        sys.exit("bench_spheres3d --sample printed no row:\n" + out)
    head = [c.strip() for c in out.splitlines()[0].strip("|").split("|")]
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    r = dict(zip(head, cells))
    return {"code": "grainpack", "spheres": int(r["spheres"]), "steps": int(r["steps"]),
            "seconds": float(r["wall s"]), "cpu": float(r["CPU s"]), "process_s": wall,
            "stability": float(r["S_c"]), "stop": r["stop"], "porosity": float(r["porosity"]),
            "psd_error_pp": float(r["max PSD error (pp)"])}


def yade_row(stdout, wall, code="YADE"):
    m = re.search(r"^RESULT (\{.*\})$", stdout, re.M)
    if not m:
        return None
    r = json.loads(m.group(1))
    return {"code": code, "spheres": r["spheres"], "steps": r["steps"], "seconds": r["time_s"],
            "cpu": r.get("cpu_s", float("nan")), "process_s": wall, "stability": r["stability"],
            "stop": "stable" if r["stability"] <= 1e-4 else "not stable",
            "porosity": r["porosity"], "psd_error_pp": r["psd_error_pp"]}


def run_yade(seed):
    script = os.path.join(HERE, "peers", "yade_dang_meguid.py")
    t0 = time.time()
    p = subprocess.run(["yade", "-j1", "-n", "-x", script, str(seed)], capture_output=True,
                       text=True)
    row = yade_row(p.stdout, time.time() - t0)
    if row is None:
        sys.exit("yade printed no RESULT line (rc %d):\n%s\n%s" % (p.returncode, p.stdout[-3000:],
                                                                 p.stderr[-3000:]))
    return row


def best(runs):
    return min(runs, key=lambda r: r["seconds"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("build", nargs="?", default="build")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-yade", action="store_true")
    ap.add_argument("--yade-log", help="YADE's stdout from an earlier run (its RESULT line)")
    a = ap.parse_args()
    load0 = os.getloadavg()[0]
    gp = best([run_grainpack(a.build, a.seed) for _ in range(a.repeat)])
    rows = [gp]
    if a.yade_log:
        with open(a.yade_log) as f:
            row = yade_row(f.read(), float("nan"), "YADE (earlier run: %s)" % a.yade_log)
        if row is None:
            sys.exit("no RESULT line in " + a.yade_log)
        rows.append(row)
    elif not a.no_yade:
        rows.append(best([run_yade(a.seed) for _ in range(a.repeat)]))
    load1 = os.getloadavg()[0]
    print("## Dang & Meguid sample (0.5 m cube, Table 2 sieve, porosity 0.38, S_c <= 1e-4), "
          "1 thread, seed %d, load average %.2f -> %.2f on %d CPUs" % (a.seed, load0, load1,
                                                                     os.cpu_count()))
    print("| code | spheres | steps | seconds | CPU s | M sphere-steps/s | S_c | stop | porosity | "
          "porosity error | max PSD error by weight (pp) | time / grainpack's | CPU / grainpack's |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %d | %d | %.2f | %.2f | %.2f | %.2g | %s | %.4f | %+.4f | %.2g | %.1fx | %.1fx |" % (
            r["code"], r["spheres"], r["steps"], r["seconds"], r["cpu"],
            r["spheres"] * r["steps"] / r["seconds"] / 1e6, r["stability"], r["stop"],
            r["porosity"], r["porosity"] - TARGET_POROSITY, r["psd_error_pp"],
            r["seconds"] / gp["seconds"], r["cpu"] / gp["cpu"]))


if __name__ == "__main__":
    main()
