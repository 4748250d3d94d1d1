#!/usr/bin/env python3
"""bench_transfer.py -- did the flip keep the sample's structure? stats.transfer of the paper's
sample S0 (the contract's 3D example: 0.5 m cube, the Table-2 sieve, porosity 0.38) for several
seeds, each tiled 2 x 2 x 2 and 4 x 4 x 4, through the daemon; the sample's seed-to-seed scatter
beside each figure of the final packing.

    python3 bench/bench_transfer.py build/server/grainpackd [--seeds 7,8,9] [--svg FILE]

Starts grainpackd on a free port with a temporary database (2 workers), submits one spheres-3d
job per seed and tiling, and prints one table: the seconds of each job, and for each figure of
stats.transfer the sample's mean and seed-to-seed sd over the seeds, and the largest difference
final - sample over the jobs, with the verdict "within" (|difference| <= 2 sd of the samples)
or the reason it is not. g(r): the largest |g_final - g_sample| of each job against the largest
|g_a - g_b| between two seeds' samples (the floor the seeds themselves show). --svg writes the
transfer view of the first seed's 4 x 4 x 4 job (the README's picture).
Python standard library only.
"""
import argparse
import json
import math
import os
import statistics
import sys
import tempfile
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_export import start, stop  # noqa: E402

SPEC = {"kind": "spheres-3d", "box": [0.5, 0.5, 0.5], "porosity": 0.38, "outputs": ["fabric"]}
TILINGS = ([2, 2, 2], [4, 4, 4])


def get(url, body=None, raw=False):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method="POST" if data else "GET",
                                 headers={"Content-Type": "application/json"} if data else {})
    with urllib.request.urlopen(req, timeout=600) as r:
        b = r.read()
        return b if raw else json.loads(b)


def run_all(url, seeds):
    """Submits every job at once (the daemon queues them), then waits: {(seed, tiling): (id,
    summary, seconds)}."""
    jobs = {}
    for seed in seeds:
        for t in TILINGS:
            jobs[(seed, tuple(t))] = get(url + "/v1/jobs", dict(SPEC, seed=seed, tiling=t))["id"]
    out = {}
    for key, jid in jobs.items():
        while True:
            j = get(url + "/v1/jobs/" + jid)
            if j["status"] in ("succeeded", "failed", "cancelled"):
                break
            time.sleep(1)
        if j["status"] != "succeeded":
            sys.exit("job %s %s: %s" % (key, j["status"], j["error"]))
        s = get(url + "/v1/jobs/%s/summary" % jid)
        out[key] = (jid, s, s["timings"]["total"])
    return out


def diag(m):
    return [m[i][i] for i in range(3)]


def offdiag_max(m):
    return max(abs(m[i][j]) for i in range(3) for j in range(3) if i != j)


# the figures: name, value of one side ("sample" or "final") of a stats.transfer
FIGURES = [
    ("porosity", lambda t, s: t["porosity"][s]),
    ("coordination (walls counted)", lambda t, s: t["coordination_number"][s]),
    ("coordination (sphere pairs)", lambda t, s: t["coordination_spheres"][s]),
    ("fabric xx", lambda t, s: diag(t["fabric"][s])[0]),
    ("fabric yy", lambda t, s: diag(t["fabric"][s])[1]),
    ("fabric zz", lambda t, s: diag(t["fabric"][s])[2]),
    ("fabric, largest off-diagonal", lambda t, s: offdiag_max(t["fabric"][s])),
    ("d50 by weight (mm)", lambda t, s: 1e3 * t["psd"]["d50"][s]),
]

WHY = {
    "coordination (sphere pairs)": "the sample's wall contacts on inner faces become pairs "
                                   "with the mirror image (walls counted: identical)",
    "fabric, largest off-diagonal": "mirrors cancel the off-diagonal terms along an axis with "
                                    "an even number of tiles",
}


def rdf_of(res, key):
    return res[key][1]["stats"]["transfer"]["rdf"]


def rdf_floor(res, seeds, rmin=0.0):
    """The largest |g_a - g_b| between two seeds' samples (bin by bin, r in d50 units, r > rmin
    d50)."""
    g = [rdf_of(res, (s, (2, 2, 2))) for s in seeds]
    worst = 0.0
    for i in range(len(g)):
        for j in range(i + 1, len(g)):
            worst = max(worst, max(abs(a - b) for a, b, r in zip(g[i]["sample"], g[j]["sample"],
                                                                 g[i]["r_d50"]) if r > rmin))
    return worst


def rdf_diff(rd, rmin):
    """(g_final - g_sample of the largest |difference| at r > rmin d50, where)"""
    return max(((f - s, r) for f, s, r in zip(rd["final"], rd["sample"], rd["r_d50"])
                if r > rmin), key=lambda d: abs(d[0]))


def table(res, seeds):
    print("| figure | sample, mean ± sd over seeds %s | final − sample, largest over the jobs "
          "(2×2×2 / 4×4×4) | verdict |" % ",".join(map(str, seeds)))
    print("|---|---|---|---|")
    for name, f in FIGURES:
        samples = [f(res[(s, (2, 2, 2))][1]["stats"]["transfer"], "sample") for s in seeds]
        sd = statistics.stdev(samples) if len(samples) > 1 else 0.0
        worst = {}
        for t in TILINGS:
            d = [f(res[(s, tuple(t))][1]["stats"]["transfer"], "final") -
                 f(res[(s, tuple(t))][1]["stats"]["transfer"], "sample") for s in seeds]
            worst[tuple(t)] = max(d, key=abs)
        w = max(abs(v) for v in worst.values())
        verdict = "within" if w <= 2 * sd else WHY.get(name, "OUTSIDE 2 sd")
        print("| %s | %.6g ± %.3g | %+.3g / %+.3g | %s |" % (
            name, statistics.mean(samples), sd, worst[(2, 2, 2)], worst[(4, 4, 4)], verdict))
    for what in ("psd_number", "psd_weight"):
        w = max(res[k][1]["stats"]["transfer"]["max_difference"][what] for k in res)
        print("| PSD by %s, percent passing | — | %.3g pp largest | %s |" % (
            what[4:], w, "identical" if w == 0 else "differs"))
    # g(r): every bin, then beyond the first bins of contacts (r > 0.25 d50: the smallest
    # spheres' contacts, 10-12.5 mm for the paper's sieve, are where the mirrors add pairs)
    for rmin in (0.0, 0.25):
        floor = rdf_floor(res, seeds, rmin)
        for t in TILINGS:
            rd = [rdf_diff(rdf_of(res, (s, tuple(t))), rmin) for s in seeds]
            cells = ", ".join("%+.3f at %.3g d50" % d for d in rd)
            w = max(abs(d[0]) for d in rd)
            print("| g(r) %s, r > %g d50: g_final − g_sample, largest (seeds %s) | floor "
                  "between two seeds' samples: %.3f | %s | %s |" % (
                      "×".join(map(str, t)), rmin, ",".join(map(str, seeds)), floor, cells,
                      "within the floor" if w <= floor else "ABOVE the floor"))
    print()
    print("| job | spheres | seconds (2 workers of 1 thread) |")
    print("|---|---|---|")
    for (seed, t), (jid, s, sec) in sorted(res.items()):
        print("| seed %d, %s | %d | %.1f |" % (seed, "×".join(map(str, t)),
                                              s["stats"]["particles"], sec))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--seeds", default="7,8,9")
    ap.add_argument("--svg", help="write the transfer view of the first seed's 4x4x4 job here")
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    tmp = tempfile.mkdtemp(prefix="gp-bench-transfer-")
    proc, url = start(os.path.abspath(a.binary), os.path.join(tmp, "jobs.db"), 2)
    try:
        res = run_all(url, seeds)
        table(res, seeds)
        if a.svg:
            jid = res[(seeds[0], (4, 4, 4))][0]
            with open(a.svg, "wb") as f:
                f.write(get(url + "/v1/jobs/%s/svg?view=transfer&width=720" % jid, raw=True))
            print("\nwrote %s (job %s)" % (a.svg, jid))
    finally:
        stop(proc)


if __name__ == "__main__":
    main()
