#!/usr/bin/env python3
"""bench_triax_peers.py -- grainpack's triaxial test against YADE's on the very same S0, in one
run (the triaxial-3d issue's benchmark): S0 at 50 kPa to 20 % of axial strain at 0.01 /s.

    python3 bench/bench_triax_peers.py [BUILD] [--yade-json FILE] [--tilings [2,4]]
        [--estimate-above 600] [--job-threads 1] [--seed 7] [--confining 50] [--rate 0.01]
        [--strain 0.2] [--work DIR] [--json FILE] [--no-build]

BUILD (default build/ of this checkout; `cmake --build BUILD --target bench_triax` is run first
unless --no-build, and grainpackd too with --tilings):
1. grainpack: `BUILD/bench/bench_triax SEED --json W/grainpack.json --export W/s0` (the core on
   one thread: the paper's S0, 0.5 m cube, Tables 1 and 2, porosity 0.38, seed 7: 2,430
   spheres), its seconds those of the test (consolidation and loading; the specimen's build is
   not counted), its peak memory the process's (getrusage ru_maxrss);
2. YADE: `yade -j1 -n -x bench/peers/yade_triaxial.py W/s0/spheres.txt W/s0/box.json
   W/yade.json --confining-kpa .. --strain-rate .. --axial-strain ..` (YADE's
   TriaxialStressController on exactly the spheres grainpack tests; ~15 min for S0), its
   seconds the script's own (out.json's wall_clock_s and cpu_s: loading the spheres -- under a
   second --, consolidation and loading; YADE's start-up not counted), its peak memory the
   process's (not known with --yade-json). With
   --yade-json FILE YADE's row is read from an earlier run's out.json instead: its settings must
   be this run's and its specimen this one's (the same count and solid volume; the file
   bench/peers/triaxial_specimen.py writes from the daemon is bench_triax's export bit for bit);
3. --tilings [LIST] (default 2,4): the 2x2x2 and 4x4x4 mirror tilings of S0 (19,440 and 155,520
   spheres), each tested by the daemon (its own grainpackd, a temporary SQLite database, one
   worker, --job-threads: a triaxial-3d job on the inline S0 spec with the tiling, part
   "tiled", the same test), for their seconds (the job's consolidation + loading; CPU from
   /proc between the job's entering consolidation and its end) and the daemon's peak memory
   (ru_maxrss at its exit: the build of the specimen included). A tiling whose estimate -- the
   CPU per sphere-step (the largest run's so far, extrapolated as a power of the spheres
   through the two largest) x its spheres x S0's steps -- is above --estimate-above seconds
   (600) is not run: its row gives the estimate (the memory linear in the spheres through the
   measured rows), marked ~. The cost per sphere-step grows with the size faster than that
   (short runs: 2x2x2 1.3 x S0's, 4x4x4 2.1 x), so an estimate is a lower bound.

Prints ONE markdown table (stdout): a row per code and tiling -- spheres, steps (consolidation
+ loading), dt, seconds (wall and CPU), CPU us per sphere-step, peak memory, peak sigma1/sigma3,
axial strain at the peak, phi at the peak, eps_v at 5 / 10 / 20 % (compression positive) --
and the differences grainpack - YADE with the speed ratio (YADE's seconds / grainpack's). The
machine's load average and the issue's tolerances (peak within 5 %, eps_v within 0.5
percentage points, strain at peak within +-0.03) go to stderr after it. --json FILE keeps all
the figures. Python standard library only.
"""
import argparse
import json
import math
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
PEERS = os.path.join(HERE, "peers")
sys.path.insert(0, PEERS)
import triaxial_specimen  # noqa: E402  (S0's spec, the daemon's)

TICK = os.sysconf("SC_CLK_TCK")


def log(msg):
    sys.stderr.write("bench_triax_peers: %s\n" % msg)
    sys.stderr.flush()


def run_measured(cmd, out_path, cwd=None):
    """Runs cmd (stdout and stderr to out_path); returns (exit status, wall s, CPU s, max RSS
    in MB) of the process and its children (wait4)."""
    with open(out_path, "wb") as out:
        t0 = time.time()
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, cwd=cwd)
        _, status, ru = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        wall = time.time() - t0
    return proc.returncode, wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0


def tail(path, n=3000):
    try:
        with open(path, "rb") as f:
            return f.read().decode(errors="replace")[-n:]
    except OSError:
        return ""


def interp(xs, ys, x):
    """y at axial strain x, linear between samples; the last sample stands for x when it is
    short of it by rounding only; None beyond the curve."""
    for k in range(1, len(xs)):
        if xs[k] >= x:
            x0, x1 = xs[k - 1], xs[k]
            return ys[k] if x1 == x0 else ys[k - 1] + (ys[k] - ys[k - 1]) * (x - x0) / (x1 - x0)
    if xs and x - xs[-1] <= 1e-6:
        return ys[-1]
    return None


def ev_at(curves):
    e, v = curves["axial_strain"], curves["volumetric_strain"]
    return [interp(e, v, x) for x in (0.05, 0.10, 0.20)]


def solid_volume(path):
    with open(path) as f:
        rows = [l.split() for l in f if l.strip() and not l.startswith("#")]
    return len(rows), math.fsum(4.0 / 3.0 * math.pi * float(r[3]) ** 3 for r in rows)


# ------------------------------------------------------------------------------- grainpack S0
def run_grainpack(a, work):
    js = os.path.join(work, "grainpack.json")
    exp = os.path.join(work, "s0")
    cmd = [a.bench, str(a.seed), "--confining", repr(a.confining), "--rate", repr(a.rate),
           "--strain", repr(a.strain), "--threads", "1", "--json", js, "--export", exp]
    log("grainpack: %s" % " ".join(cmd))
    outp = os.path.join(work, "bench_triax.out")
    rc, wall, cpu, rss = run_measured(cmd, outp)
    if rc != 0 or not os.path.exists(js):
        sys.exit("bench_triax failed (exit %d):\n%s" % (rc, tail(outp)))
    with open(js) as f:
        g = json.load(f)
    c = g["consolidation"]
    row = {"code": "grainpack (bench_triax, core, 1 thread)", "spheres": g["spheres"],
           "steps_consolidation": c["steps"], "steps": g["steps"], "dt": g["dt"],
           "wall_s": g["wall_clock_s"], "cpu_s": g["cpu_s"], "rss_mb": rss,
           "process_wall_s": wall, "process_cpu_s": cpu,
           "peak_ratio": g["peak"]["stress_ratio"], "peak_strain": g["peak"]["axial_strain"],
           "phi_deg": g["peak"]["phi_deg"], "ev": ev_at(g["curves"]),
           "porosity_consolidated": c["porosity"],
           "inertial_number_max": g["inertial_number_max"],
           "servo_error_max": g["servo_error_max"]}
    log("grainpack: %d spheres, peak %.4f at %.4f, %.1f s wall, %.1f s CPU (the test), %.0f MB"
        % (row["spheres"], row["peak_ratio"], row["peak_strain"], row["wall_s"], row["cpu_s"],
           rss))
    return row, exp


# ------------------------------------------------------------------------------------ YADE S0
def yade_row(y, rss, source):
    return {"code": "YADE %s (yade_triaxial.py, 1 thread)" % y.get("yade_version", "?"),
            "spheres": y["spheres"], "steps_consolidation": y["consolidation"]["steps"],
            "steps": y["steps"], "dt": y["dt"], "wall_s": y["wall_clock_s"], "cpu_s": y["cpu_s"],
            "rss_mb": rss, "peak_ratio": y["peak"]["stress_ratio"],
            "peak_strain": y["peak"]["axial_strain"], "phi_deg": y["peak"]["phi_deg"],
            "ev": ev_at(y["curves"]), "porosity_consolidated": y["consolidation"]["porosity"],
            "inertial_number_max": y["inertial_number_max"],
            "servo_error_max": y["servo_error_max"], "source": source,
            "consolidation_stop": y["consolidation"].get("stop_reason")}


def check_yade_settings(y, a):
    """An earlier out.json stands in only for this run's test (checked before anything runs)."""
    s = y.get("settings", {})
    want = {"confining_kpa": a.confining, "strain_rate": a.rate, "axial_strain": a.strain}
    for k, v in want.items():
        if not (isinstance(s.get(k), (int, float)) and abs(s[k] - v) <= 1e-12 * abs(v)):
            sys.exit("--yade-json: its %s is %r, this run's %r" % (k, s.get(k), v))
    if y.get("status") != "done":
        sys.exit("--yade-json: status %r (a partial run?)" % y.get("status"))


def check_yade_specimen(y, exp):
    """... and on this run's specimen (bench_triax's export)."""
    n, vol = solid_volume(os.path.join(exp, "spheres.txt"))
    sp = y.get("specimen", {})
    if sp.get("spheres") != n or abs(sp.get("solid_volume", 0) - vol) > 1e-12 * vol:
        sys.exit("--yade-json: its specimen (%r spheres, solid %r m3) is not bench_triax's "
                 "(%d, %r)" % (sp.get("spheres"), sp.get("solid_volume"), n, vol))


def run_yade(a, work, exp):
    out = os.path.join(work, "yade.json")
    yade = shutil.which(a.yade)
    if not yade:
        sys.exit("no `%s` on PATH (Debian's yade: deploy/install-deps.sh --test), or pass "
                 "--yade-json FILE" % a.yade)
    cmd = [yade, "-j1", "-n", "-x", os.path.join(PEERS, "yade_triaxial.py"),
           os.path.join(exp, "spheres.txt"), os.path.join(exp, "box.json"), out,
           "--confining-kpa", repr(a.confining), "--strain-rate", repr(a.rate),
           "--axial-strain", repr(a.strain)]
    log("YADE (about 15 min for S0): %s" % " ".join(cmd))
    logp = os.path.join(work, "yade.log")
    rc, wall, cpu, rss = run_measured(cmd, logp, cwd=work)
    if rc != 0 or not os.path.exists(out):
        sys.exit("YADE failed (exit %d):\n%s" % (rc, tail(logp)))
    with open(out) as f:
        y = json.load(f)
    return yade_row(y, rss, out)


# ------------------------------------------------------------------------- tilings (daemon)
def http(url, method="GET", body=None, timeout=60):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method=method,
                                 headers={"Content-Type": "application/json"} if data else {})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, json.loads(r.read() or b"null")
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read() or b"null")


def proc_cpu(pid):
    """CPU seconds (user + system) of a running process, from /proc."""
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def run_tiling(a, n, work):
    d = os.path.join(work, "tiling-%d" % n)
    os.makedirs(d, exist_ok=True)
    cmd = [a.grainpackd, "--listen", "127.0.0.1:0", "--db", os.path.join(d, "jobs.db"),
           "--workers", "1", "--job-threads", str(a.job_threads), "--job-timeout", "0"]
    logf = open(os.path.join(d, "grainpackd.log"), "wb")
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=logf)
    reaped = None
    try:
        line = b""
        deadline = time.time() + 30
        while not line.endswith(b"\n"):
            if time.time() > deadline or proc.poll() is not None:
                sys.exit("grainpackd did not start:\n" + tail(logf.name))
            if select.select([proc.stdout], [], [], 1)[0]:
                line += os.read(proc.stdout.fileno(), 1)
        base = line.decode().strip()[len("listening on "):]
        spec = triaxial_specimen.make_spec(seed=a.seed)
        spec["tiling"] = [n, n, n]
        spec["outputs"] = ["spheres"]
        job = {"kind": "triaxial-3d", "seed": a.seed,
               "specimen": {"spec": spec, "part": "tiled"}, "confining_kpa": [a.confining],
               "axial_strain": a.strain, "strain_rate": a.rate, "drainage": "drained",
               "outputs": ["curves"]}
        st, j = http(base + "/v1/jobs", "POST", job)
        if st != 201:
            sys.exit("tiling %d: submit refused: %d %s" % (n, st, j))
        jid = j["id"]
        log("tiling %dx%dx%d: job %s on %s" % (n, n, n, jid, base))
        t0 = time.time()
        cpu_test0 = None
        last_phase, last_log = None, 0.0
        while True:
            st, job = http(base + "/v1/jobs/" + jid)
            phase = job["progress"]["phase"]
            if cpu_test0 is None and phase in ("consolidation", "loading"):
                cpu_test0 = proc_cpu(proc.pid)
            if job["status"] in ("succeeded", "failed", "cancelled"):
                break
            if phase != last_phase or time.time() - last_log >= 60:
                log("  %7.0f s  %s %.0f %%, eta %s s" % (
                    time.time() - t0, phase, 100 * job["progress"]["fraction"],
                    job["progress"]["eta_s"]))
                last_phase, last_log = phase, time.time()
            time.sleep(1.0)
        cpu_end = proc_cpu(proc.pid)
        if job["status"] != "succeeded":
            sys.exit("tiling %d: job %s: %s" % (n, job["status"], job.get("error")))
        st, r = http(base + "/v1/jobs/%s/result" % jid, timeout=600)
        proc.send_signal(signal.SIGTERM)
        _, status, ru = os.wait4(proc.pid, 0)
        reaped = True
    finally:
        if not reaped and proc.poll() is None:
            proc.kill()
            proc.wait(10)
        proc.stdout.close()
        logf.close()
    t = r["stats"]["tests"][0]
    tm = r["timings"]
    return {"code": "grainpack %dx%dx%d (daemon, %d job thread%s)" % (
                n, n, n, a.job_threads, "" if a.job_threads == 1 else "s"),
            "spheres": r["stats"]["particles"], "steps_consolidation": t["consolidation"]["steps"],
            "steps": t["steps"], "dt": t["dt"], "wall_s": tm["consolidation"] + tm["loading"],
            "cpu_s": cpu_end - (cpu_test0 if cpu_test0 is not None else 0.0),
            "rss_mb": ru.ru_maxrss / 1024.0, "specimen_s": tm["specimen"],
            "daemon_cpu_s": ru.ru_utime + ru.ru_stime,
            "peak_ratio": t["peak"]["stress_ratio"], "peak_strain": t["peak"]["axial_strain"],
            "phi_deg": t["peak"]["phi_deg"], "ev": ev_at(r["curves"][0]),
            "porosity_consolidated": t["consolidation"]["porosity"],
            "inertial_number_max": t["inertial_number_max"],
            "servo_error_max": t["servo_error_max"], "warnings": r["warnings"]}


def sphere_step_cost(measured, spheres):
    """CPU seconds per sphere-step at this many spheres: the largest run's measured cost,
    extrapolated as a power of the spheres through the two largest runs when there are two
    (the cost grows with the size -- the caches: on short runs 2x2x2 cost 1.3 x S0's and 4x4x4
    2.1 x, faster than a power law, so the estimate stays low)."""
    runs = sorted(measured, key=lambda m: m["spheres"])
    cost = [m["cpu_s"] / (m["spheres"] * m["steps"]) for m in runs]
    big = runs[-1]
    if len(runs) >= 2 and runs[-2]["spheres"] < big["spheres"] and cost[-1] > cost[-2]:
        k = math.log(cost[-1] / cost[-2]) / math.log(big["spheres"] / runs[-2]["spheres"])
        return cost[-1] * (spheres / big["spheres"]) ** k, big
    return cost[-1], big


def estimate_tiling(n, gp, measured):
    """A tiling not run: the CPU per sphere-step of the largest run measured x its spheres x
    S0's steps (the same dt: the same smallest sphere); memory linear in the spheres through
    the measured rows."""
    spheres = gp["spheres"] * n ** 3
    us, _ = sphere_step_cost(measured, spheres)
    secs = us * spheres * gp["steps"]
    pts = sorted((m["spheres"], m["rss_mb"]) for m in measured if m.get("rss_mb"))
    if len(pts) >= 2:
        (n0, m0), (n1, m1) = pts[-2], pts[-1]
        rss = m1 + (m1 - m0) / (n1 - n0) * (spheres - n1)
    else:
        rss = gp["rss_mb"] * spheres / gp["spheres"]
    return {"code": "grainpack %dx%dx%d (estimated, not run)" % (n, n, n), "spheres": spheres,
            "steps": gp["steps"], "steps_consolidation": None, "dt": gp["dt"], "wall_s": secs,
            "cpu_s": secs, "rss_mb": rss, "estimated": True}


# ---------------------------------------------------------------------------------- the table
def num(v, f):
    return "–" if v is None else f % v


def pct(v):
    return "–" if v is None else "%+.2f %%" % (100 * v)


def table(rows, gp, yd):
    head = ["code", "spheres", "steps (consolidation + loading)", "dt (µs)", "wall s", "CPU s",
            "CPU µs / sphere-step", "peak RSS (MB)", "peak σ1/σ3", "ε_a at peak", "φ peak (°)",
            "ε_v at 5 %", "ε_v at 10 %", "ε_v at 20 %"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        est = r.get("estimated")
        t = "~" if est else ""
        if r.get("steps_consolidation") is not None:
            steps = "{:,} + {:,}".format(r["steps_consolidation"],
                                         r["steps"] - r["steps_consolidation"])
        else:
            steps = "~{:,}".format(r["steps"])
        us = 1e6 * r["cpu_s"] / (r["spheres"] * r["steps"])
        cells = [r["code"], "{:,}".format(r["spheres"]), steps, "%.2f" % (1e6 * r["dt"]),
                 t + "%.1f" % r["wall_s"], t + "%.1f" % r["cpu_s"], t + "%.3f" % us,
                 num(r.get("rss_mb"), t + "%.0f")]
        if est:
            cells += ["–"] * 6
        else:
            cells += ["%.4f" % r["peak_ratio"], "%.2f %%" % (100 * r["peak_strain"]),
                      "%.2f" % r["phi_deg"]] + [pct(v) for v in r["ev"]]
        lines.append("| " + " | ".join(cells) + " |")
    if gp and yd:
        def dpp(a, b):
            return "–" if a is None or b is None else "%+.2f pp" % (100 * (a - b))
        us_g = gp["cpu_s"] / (gp["spheres"] * gp["steps"])
        us_y = yd["cpu_s"] / (yd["spheres"] * yd["steps"])
        cells = ["**grainpack − YADE** (speed: YADE / grainpack)",
                 "%+d" % (gp["spheres"] - yd["spheres"]),
                 "{:+,} ({:.2f} x YADE's)".format(gp["steps"] - yd["steps"],
                                                   gp["steps"] / yd["steps"]),
                 "%+.2f" % (1e6 * (gp["dt"] - yd["dt"])),
                 "%.1f x faster" % (yd["wall_s"] / gp["wall_s"]),
                 "%.1f x faster" % (yd["cpu_s"] / gp["cpu_s"]),
                 "%.1f x faster" % (us_y / us_g),
                 "–" if not yd.get("rss_mb") else "%+.0f" % (gp["rss_mb"] - yd["rss_mb"]),
                 "%+.4f (%+.2f %%)" % (gp["peak_ratio"] - yd["peak_ratio"],
                                       100 * (gp["peak_ratio"] / yd["peak_ratio"] - 1)),
                 dpp(gp["peak_strain"], yd["peak_strain"]),
                 "%+.2f" % (gp["phi_deg"] - yd["phi_deg"])] + \
                [dpp(a, b) for a, b in zip(gp["ev"], yd["ev"])]
        lines.insert(4, "| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def verdicts(gp, yd):
    out = []
    rel = gp["peak_ratio"] / yd["peak_ratio"] - 1
    out.append("peak sigma1/sigma3 %+.2f %% (tolerance 5 %%): %s" % (
        100 * rel, "ok" if abs(rel) <= 0.05 else "OUTSIDE"))
    for x, a, b in zip((5, 10, 20), gp["ev"], yd["ev"]):
        if a is None or b is None:
            continue
        out.append("eps_v at %d %% %+.2f pp (tolerance 0.5 pp): %s" % (
            x, 100 * (a - b), "ok" if abs(a - b) <= 0.005 else "OUTSIDE"))
    d = gp["peak_strain"] - yd["peak_strain"]
    out.append("strain at peak %+.4f (tolerance 0.03): %s" % (d, "ok" if abs(d) <= 0.03
                                                               else "OUTSIDE"))
    out.append("porosity after consolidation: grainpack %.4f, YADE %.4f; I max %.2e / %.2e; "
               "servo error max %.2e / %.2e" % (
                   gp["porosity_consolidated"], yd["porosity_consolidated"],
                   gp["inertial_number_max"], yd["inertial_number_max"],
                   gp["servo_error_max"], yd["servo_error_max"]))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("build", nargs="?", default=os.path.join(REPO, "build"))
    ap.add_argument("--yade-json", help="YADE's row from an earlier yade_triaxial.py out.json")
    ap.add_argument("--yade", default="yade", help="the YADE program")
    ap.add_argument("--tilings", nargs="?", const="2,4", default=None,
                    help="also the daemon's test of these tilings of S0 (default 2,4)")
    ap.add_argument("--estimate-above", type=float, default=600.0,
                    help="estimate (do not run) a tiling whose estimate is above this (s)")
    ap.add_argument("--job-threads", type=int, default=1, help="the tilings' DEM threads")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--confining", type=float, default=50.0, help="kPa")
    ap.add_argument("--rate", type=float, default=0.01, help="1/s")
    ap.add_argument("--strain", type=float, default=0.2, help="axial strain at the end")
    ap.add_argument("--work", help="keep the files here (default: a temporary folder)")
    ap.add_argument("--json", help="write all the figures to this file")
    ap.add_argument("--no-build", action="store_true")
    a = ap.parse_args()
    a.build = os.path.abspath(a.build)
    a.bench = os.path.join(a.build, "bench", "bench_triax")
    a.grainpackd = os.path.join(a.build, "server", "grainpackd")
    if not a.no_build:
        targets = ["bench_triax"] + (["grainpackd"] if a.tilings else [])
        r = subprocess.run(["cmake", "--build", a.build, "-j2", "--target"] + targets,
                           capture_output=True, text=True)
        if r.returncode:
            sys.exit("cmake --build %s failed:\n%s" % (a.build, (r.stdout + r.stderr)[-3000:]))
    for path in [a.bench] + ([a.grainpackd] if a.tilings else []):
        if not os.access(path, os.X_OK):
            sys.exit("no %s: cmake --build %s --target %s" % (path, a.build,
                                                              os.path.basename(path)))
    tilings = [int(v) for v in a.tilings.split(",")] if a.tilings else []
    work = a.work or tempfile.mkdtemp(prefix="bench-triax-peers-")
    os.makedirs(work, exist_ok=True)
    y = None
    if a.yade_json:
        with open(a.yade_json) as f:
            y = json.load(f)
        check_yade_settings(y, a)
    load0 = os.getloadavg()
    try:
        gp, exp = run_grainpack(a, work)
        if y is not None:
            check_yade_specimen(y, exp)
            yd = yade_row(y, None, os.path.abspath(a.yade_json))
            yd["code"] += " (earlier run: --yade-json)"
        else:
            yd = run_yade(a, work, exp)
        rows = [gp, yd]
        measured = [gp]
        for n in tilings:
            us, base = sphere_step_cost(measured, gp["spheres"] * n ** 3)
            est = us * gp["spheres"] * n ** 3 * gp["steps"]
            if a.estimate_above and est > a.estimate_above:
                log("tiling %dx%dx%d: estimated %.0f s (%.1f h of CPU: %.3f us per sphere-step "
                    "from %s) > %g s: not run" % (n, n, n, est, est / 3600, 1e6 * us,
                                                  base["code"], a.estimate_above))
                rows.append(estimate_tiling(n, gp, measured))
            else:
                log("tiling %dx%dx%d: estimated %.0f s: running" % (n, n, n, est))
                t = run_tiling(a, n, work)
                measured.append(t)
                rows.append(t)
        load1 = os.getloadavg()
        print(table(rows, gp, yd))
        sys.stdout.flush()
        for v in verdicts(gp, yd):
            log(v)
        log("S0 at %g kPa, %g /s to %g %%, seed %d; seconds: grainpack's the test (bench_triax "
            "times consolidation + loading; its process %.1f s wall, %.1f s CPU with the build), "
            "YADE's yade_triaxial.py's from its start, a tiling's the job's consolidation + loading; peak RSS "
            "ru_maxrss (a tiling's: the daemon's, specimen build included)" % (
                a.confining, a.rate, 100 * a.strain, a.seed, gp["process_wall_s"],
                gp["process_cpu_s"]))
        log("load average %.2f at the start, %.2f at the end (%d cores)" % (
            load0[0], load1[0], os.cpu_count()))
        if a.json:
            with open(a.json, "w") as f:
                json.dump({"settings": {k: getattr(a, k) for k in (
                    "seed", "confining", "rate", "strain", "job_threads", "estimate_above")},
                    "rows": rows, "load_average": [load0[0], load1[0]],
                    "work": work}, f, indent=1)
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
