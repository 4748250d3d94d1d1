#!/usr/bin/env python3
"""bench_large2d.py -- large 2D specimens end to end through the API, with the daemon's memory.

    python3 bench/bench_large2d.py build/server/grainpackd [--million] [--rows a,b,...]
                                   [--max-result-mb MB] [--keep]

Starts grainpackd (one worker, a temporary database) and runs, one job at a time:
  mz12        Mollon & Zhao (2012) Example 1 on the idle daemon (500 grains in a unit square,
              size COV 0.8, anisotropy 1, D2/D3/D8 0.1/0.06/0.03, F_S 0.65, seed 2012;
              outputs grains, odec, descriptors)
  10k         10,000 grains (size COV 0.5; outputs grains, odec, descriptors)
  100k        100,000 grains (outputs odec)
  mz12-after  Example 1 again, submitted once the job above (100k) has succeeded and a second
              later its result was fetched (as every row's: the table's result columns) -- the
              daemon's checkpoint of that job's commit is then due or running
  1M          (with --million) 1,000,000 grains (outputs odec)
and prints one table, a row a job:
  s        seconds from submit to status succeeded, as a client sees it (polling every 0.05 s);
  daemon s finished_at - created_at of the job object, the daemon's own stamps (milliseconds):
           finished_at is taken as the final store begins, so s - daemon s is that store's
           commit plus the client's poll;
  peak MB  the daemon's largest VmRSS sampled every 0.05 s during the job (VmHWM cannot be
           reset between rows), split into the build (the core's phases) and the result
           phase (writing the text, the export pack, storing); HWM: VmHWM so far;
  idle MB  RssAnon once the job is stored (the freed heap handed back or not; file pages the
           kernel maps, such as the database's shared WAL index, are not counted);
  result   MB of GET /result (10^6 bytes, streamed and counted, not kept) and bytes a grain;
  sha256   the first 12 hex digits of the SHA-256 of GET /result with the value of its "timings"
           member (seconds, the one part that varies run to run) written as null: the same spec
           and seed give the same bytes whatever build or store wrote them (compare two runs);
  error    what the specimen achieved, from GET /summary: solid fraction target -> achieved,
           the IMC error over its threshold, and the fit report's KS distances over their 5 %
           critical values for cell areas, grain areas and cell orientations (<= 1 passes).
A job the daemon refuses or fails shows its error instead. Linux only (/proc); Python standard
library only (bench_export.py's helpers).
"""
import argparse
import calendar
import hashlib
import os
import shutil
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_export import call, download, start, stop  # noqa: E402

SQUARE = {"polygon": [[0, 0], [1, 0], [1, 1], [0, 1]], "holes": []}
MZ12 = {"kind": "fourier-voronoi-2d", "seed": 2012, "container": SQUARE, "particles": 500,
        "size": {"cov": 0.8}, "orientation": {"mean_deg": 0, "anisotropy": 1.0},
        "shape": {"D2": 0.1, "D3": 0.06, "D8": 0.03}, "solid_fraction": 0.65,
        "outputs": ["grains", "odec", "descriptors"]}


def large(n, outputs):
    return {"kind": "fourier-voronoi-2d", "seed": 7, "container": SQUARE, "particles": n,
            "size": {"cov": 0.5}, "outputs": outputs}


ROWS = {
    "mz12": ("MZ12 Example 1, idle daemon", MZ12),
    "10k": ("10,000 grains (grains, odec, descr.)", large(10000, ["grains", "odec", "descriptors"])),
    "100k": ("100,000 grains (odec)", large(100000, ["odec"])),
    "mz12-after": ("MZ12 Example 1 right after the job above", MZ12),
    "1M": ("1,000,000 grains (odec)", large(1000000, ["odec"])),
}


def vm(pid, key):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) / 1024.0  # MB (MiB)
    return float("nan")


def rfc3339_s(t):
    """seconds since the epoch of the daemon's stamps, 2026-12-01T20:45:00.123Z"""
    if not t:
        return float("nan")
    whole, _, frac = t.rstrip("Z").partition(".")
    return calendar.timegm(time.strptime(whole, "%Y-%m-%dT%H:%M:%S")) + float("0." + (frac or "0"))


def run_job(base, pid, spec):
    """Submits spec and samples the daemon every 0.05 s until the job ends."""
    t0 = time.perf_counter()
    st, j = call(base + "/v1/jobs", "POST", spec)
    if st != 201:
        return {"error": "%s %s" % (st, j.get("error", j) if isinstance(j, dict) else j)}
    jid = j["id"]
    peak = {"build": 0.0, "result": 0.0}
    while True:
        rss = vm(pid, "VmRSS")
        st, j = call(base + "/v1/jobs/" + jid)
        status = j.get("status")
        if status in ("succeeded", "failed", "cancelled"):
            dt = time.perf_counter() - t0
            break
        phase = (j.get("progress") or {}).get("phase", "")
        key = "result" if phase == "result" else "build"
        peak[key] = max(peak[key], rss)
        time.sleep(0.05)
    out = {"id": jid, "s": dt, "peak_build": peak["build"], "peak_result": peak["result"],
           "hwm": vm(pid, "VmHWM"),
           "daemon_s": rfc3339_s(j.get("finished_at")) - rfc3339_s(j.get("created_at"))}
    if status != "succeeded":
        err = j.get("error") or {}
        out["error"] = "%s: %s" % (err.get("code", status), err.get("message", ""))
    return out


TIMINGS = b'"timings":{'


def download_sha(url):
    """GET url in 1 MB pieces, counted and hashed, not kept: (status, bytes, sha256 hex of the
    text with the "timings" object -- flat, near the head -- replaced by null)."""
    h = hashlib.sha256()
    st = {"head": b""}  # the text until the timings object has been passed (a few KB)

    def each(b):
        if st["head"] is None:
            h.update(b)
            return
        head = st["head"] + b
        i = head.find(TIMINGS)
        j = head.find(b"}", i) if i >= 0 else -1
        if j >= 0:
            h.update(head[:i] + b'"timings":null' + head[j + 1:])
            head = None
        elif len(head) > (16 << 20):  # no timings: the text as it is
            h.update(head)
            head = None
        st["head"] = head

    status, n = download(url, each)
    if st["head"]:
        h.update(st["head"])
    return status, n, h.hexdigest()


def describe(base, jid, n):
    """Result size and hash and the error columns, from /result and /summary."""
    st, nbytes, sha = download_sha(base + "/v1/jobs/%s/result" % jid)
    st, summ = call(base + "/v1/jobs/%s/summary" % jid)
    stats = summ.get("stats", {}) if isinstance(summ, dict) else {}
    fit = stats.get("fit", {})

    def ratio(block):
        b = fit.get(block) or {}
        ks, crit = b.get("ks"), b.get("ks_critical")
        return "%.2f" % (ks / crit) if ks is not None and crit else "-"

    sf = stats.get("solid_fraction", {})
    imc = stats.get("imc_error", {})
    sfa = sf.get("achieved")
    return {"mb": nbytes / 1e6, "per": nbytes / n, "sha": sha[:12],
            "sf": "%.2f -> %s" % (sf.get("target", float("nan")),
                                  "%.4f" % sfa if sfa is not None else "-"),
            "imc": "%.3g/%.3g" % (imc.get("achieved", float("nan")), imc.get("target", float("nan"))),
            "cell": ratio("cell_area"), "grain": ratio("grain_area"),
            "orient": ratio("cell_orientation")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--million", action="store_true", help="add the 1,000,000-grain row")
    ap.add_argument("--rows", help="comma-separated subset of " + ",".join(ROWS))
    ap.add_argument("--max-result-mb", type=int, help="the daemon's --max-result-mb")
    ap.add_argument("--keep", action="store_true", help="keep the temporary database")
    a = ap.parse_args()
    rows = a.rows.split(",") if a.rows else [r for r in ROWS if r != "1M" or a.million]

    tmp = tempfile.mkdtemp(prefix="bench-large2d-")
    if a.max_result_mb:
        os.environ["GRAINPACK_MAX_RESULT_MB"] = str(a.max_result_mb)
    proc, base = start(os.path.abspath(a.binary), os.path.join(tmp, "bench.db"), 1)
    pid = proc.pid
    table = []
    try:
        for r in rows:
            name, spec = ROWS[r]
            print("  %s ..." % name, file=sys.stderr, flush=True)
            res = run_job(base, pid, spec)
            time.sleep(1.0)  # the worker's malloc_trim after the job
            res["idle"] = vm(pid, "RssAnon")
            if "error" not in res:
                res.update(describe(base, res["id"], spec["particles"]))
            table.append((name, res))
    finally:
        stop(proc)
        if not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    load = os.getloadavg()
    print("2D specimens through the API (1 worker; load average %.2f %.2f %.2f; %d CPUs)"
          % (load[0], load[1], load[2], os.cpu_count()))
    fmt = ("| %-36s | %7s | %8s | %8s | %8s | %7s | %7s | %8s | %6s | %-12s | %-13s | %-13s | %5s "
           "| %5s | %5s |")
    print(fmt % ("job", "s", "daemon s", "peak MB", "of which", "HWM MB", "idle MB", "result", "B/grain",
                 "sha256", "SF tgt -> ach", "IMC err/thr", "cell", "grain", "orient"))
    print(fmt % ("", "", "", "build", "result", "", "", "MB", "", "of /result", "", "", "KS/c",
                 "KS/c", "KS/c"))
    print("|" + "|".join("-" * w for w in (38, 9, 10, 10, 10, 9, 9, 10, 8, 14, 15, 15, 7, 7, 7))
          + "|")
    for name, r in table:
        if "error" in r and "s" not in r:
            print("| %-36s | refused: %s" % (name, r["error"]))
            continue
        head = "| %-36s | %7.2f | %8.2f | %8.0f | %8.0f | %7.0f | %7.0f |" % (
            name, r["s"], r["daemon_s"], r["peak_build"], r["peak_result"], r["hwm"], r["idle"])
        if "error" in r:
            print(head + " failed: %s" % r["error"])
        else:
            print(head + " %8.1f | %6.0f | %-12s | %-13s | %-13s | %5s | %5s | %5s |" % (
                r["mb"], r["per"], r["sha"], r["sf"], r["imc"], r["cell"], r["grain"],
                r["orient"]))


if __name__ == "__main__":
    main()
