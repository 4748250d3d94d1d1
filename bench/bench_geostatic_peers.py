#!/usr/bin/env python3
"""bench_geostatic_peers.py -- the geostatic settling of a tiled packing in grainpack and in
LAMMPS, side by side: which to use when.

    python3 bench/bench_geostatic_peers.py build/server/grainpackd [--tiling 4,4,4] [--np 2]
        [--minutes 60] [--seed 7] [--phi 23.73] [--keep DIR]

Starts grainpackd on a free port with a temporary database (one worker on every core), builds
the contract's 3D example (the paper's sample S0, seed 7) tiled as asked, then
1. grainpack: a geostatic-3d job on it (gravity -z, frictionless walls, the top free, until
   S_c <= 1e-4): its steps, time step, S_c, seconds, the daemon's peak memory during the job
   (VmHWM, reset before it), K0 and the equilibrium error, the surface height;
2. LAMMPS: the same packing's lammps-relax export (grainpack's contact law, damping and density
   scaling, as LAMMPS 29Sep2021 runs them), run with `mpirun -np N lmp -in relax.in -var ztop Z`,
   Z twice the box's top so that the surface is free as in 1, until S_c <= 1e-4 or --minutes:
   steps, S_c, seconds, memory (log.lammps, all ranks), the surface height from final.dump.
Prints one table. Needs lmp (Debian lammps) and mpirun (openmpi-bin). Standard library only.
"""
import argparse
import io
import os
import re
import shutil
import sys
import tarfile
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_export import proc_status, start, stop  # noqa: E402
from bench_lammps_relax import SPEC, build, extrapolate, get, run_lammps, thermo_rows  # noqa: E402


def reset_peak(pid):
    with open("/proc/%d/clear_refs" % pid, "w") as f:
        f.write("5")  # VmHWM := VmRSS


def geostatic(url, pid, sid, phi):
    """The geostatic-3d job on the specimen job sid: (summary, seconds, peak MB)."""
    reset_peak(pid)
    spec = {"kind": "geostatic-3d", "specimen": {"job": sid}, "phi_deg": phi,
            "outputs": ["profile"]}
    _, summ, secs = build(url, spec)
    return summ, secs, proc_status(pid)["VmHWM"] / 1024.0


def lammps_memory_mb(log_path, np_):
    """The largest per-rank memory LAMMPS reports, times the ranks (MB)."""
    worst = 0.0
    with open(log_path) as f:
        for line in f:
            m = re.search(r"Per MPI rank memory allocation \(min/avg/max\) = \S+ \| \S+ \| (\S+)",
                          line)
            if m:
                worst = max(worst, float(m.group(1)))
    return worst * np_


def surface(dump_path):
    """The highest sphere top in final.dump (id type radius x y z)."""
    top, cols = 0.0, None
    with open(dump_path) as f:
        for line in f:
            if line.startswith("ITEM: ATOMS"):
                cols = line.split()[2:]
                continue
            if cols and not line.startswith("ITEM"):
                v = dict(zip(cols, line.split()))
                if "z" in v and "radius" in v:
                    top = max(top, float(v["z"]) + float(v["radius"]))
    return top


def table(st, secs, mem, rep, wall, lmem, ltop, tiling, np_, seed):
    n = st["particles"]
    f = rep["after"]
    print()
    print("| the paper's sample (seed %d) tiled %s, %d spheres, settled under gravity, top free "
          "| grainpack geostatic-3d (1 worker, 2 threads) | LAMMPS relax.in, mpirun -np %d |"
          % (seed, "x".join(map(str, tiling)), n, np_))
    print("|---|---|---|")
    print("| steps | %d | %d |" % (st["steps"], rep["steps"]))
    print("| time step | %.4g s (density scaling to the largest radius) | %.4g s (grainpack's "
          "specimen step) |" % (st["dt"], rep["dt"]))
    print("| S_c reached (Eq. 7) | %.3g%s | %.3g%s |" % (
        st["stability"], "" if st["converged"] else " (not at rest)", f["stability"],
        "" if rep["stable"] else " (stopped by the time cap)"))
    print("| seconds | %.1f | %.1f (mpirun total %.1f) |" % (secs, rep["seconds"], wall))
    print("| sphere-steps a second | %.3g | %.3g |" % (
        n * st["steps"] / max(secs, 1e-9), n * rep["steps"] / max(rep["seconds"], 1e-9)))
    print("| simulated time to rest | %.3g s | %.3g s |" % (st["steps"] * st["dt"],
                                                         rep["steps"] * rep["dt"]))
    print("| peak memory | %.0f MB (the daemon) | %.0f MB (LAMMPS's report, all ranks) |"
          % (mem, lmem))
    print("| surface height (the highest sphere top) | %.4f m | %.4f m |"
          % (st["whole"]["surface"], ltop))
    print("| porosity of the box | %.5f | %.5f |" % (st["whole"]["porosity"], f["porosity"]))
    print("| coordination number | %.4f | %.4f |" % (st["whole"]["coordination"],
                                                     f["coordination_number"]))
    print("| K0: mean ± sd over slabs (1 - sin phi' = %.3f) | %.3f ± %.3f | — (no stress "
          "measure in the script) |" % (st["k0"]["theory"], st["k0"]["mean"], st["k0"]["sd"]))
    print("| sigma_v against the weight above, worst slab | %.3g %% | — |"
          % (100 * st["equilibrium"]["max_error"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--tiling", default="4,4,4")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--np", type=int, default=2, dest="np_")
    ap.add_argument("--minutes", type=float, default=60)
    ap.add_argument("--phi", type=float, default=23.73,
                    help="phi' (deg) for K0: the triaxial tests of S0 (bench/RESULTS.md)")
    ap.add_argument("--keep", help="run LAMMPS in this folder (kept)")
    a = ap.parse_args()
    tiling = [int(x) for x in a.tiling.split(",")]
    tmp = tempfile.mkdtemp(prefix="gp-bench-geo-")
    proc, url = start(os.path.abspath(a.binary), os.path.join(tmp, "jobs.db"), 1)
    try:
        sid, spec_summ, _ = build(url, dict(SPEC, seed=a.seed, tiling=tiling))
        summ, secs, mem = geostatic(url, proc.pid, sid, a.phi)
        body = get(url + "/v1/jobs/%s/export?format=lammps-relax" % sid, raw=True)[0]
    finally:
        stop(proc)
    run_dir = a.keep or os.path.join(tmp, "run")
    os.makedirs(run_dir, exist_ok=True)
    with tarfile.open(fileobj=io.BytesIO(body), mode="r:") as t:
        t.extractall(run_dir)
    folder = os.path.join(run_dir, "lammps-relax")
    ztop = 2 * spec_summ["box"][2]
    rep, wall = run_lammps(folder, a.np_, a.minutes, 10000000, ("-var", "ztop", repr(ztop)))
    lmem = lammps_memory_mb(os.path.join(folder, "log.lammps"), a.np_)
    ltop = surface(os.path.join(folder, "final.dump"))
    table(summ["stats"], secs, mem, rep, wall, lmem, ltop, tiling, a.np_, a.seed)
    if not rep["stable"]:
        rows = thermo_rows(os.path.join(folder, "log.lammps"))
        ex = extrapolate(rows, rep["seconds"]) if rows else None
        if ex:
            print("LAMMPS extrapolated: 1e-4 in about %.0f more steps, %.1f h more at this speed"
                  % (ex[0], ex[1] / 3600))
    if not a.keep:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
