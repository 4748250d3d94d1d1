"""test_shape_jobs.py -- 2D jobs with the shape forms of issue #17 against the real daemon: what
the result says of the shape used (stats.shape, stats.descriptors.<name>.target and .sd,
timings.shape), checked against what the test itself measures on the grains' contours.

  - shape.descriptors (elongation 0.7, circularity 0.8): the targets are in the result as
    numbers, the grains' own descriptors (recomputed here from the per-grain values) meet them
    within 0.02, the spectrum used starts with D0 = 1 and has D2 > 0, and the descriptors view
    draws the red target line (svg_stats2d.c: <line class="target" ... stroke="#d62728">);
  - spread 0.2: each grain's D2 re-derived here from its contour (r(theta) about its centroid
    at 128 angles by ray-polygon intersection, then a DFT) varies from grain to grain with a
    coefficient of variation within 0.05 of 0.2 (without spread: none), and the same spec and
    seed give the same result bytes (less "timings") twice on one worker and twice at once on
    two;
  - shape.outlines (20 outlines made here from a known spectrum): the job succeeds with form
    "outlines", the outlines' mean spectrum near the known one, and their descriptor means as
    the targets;
  - a spec without a shape form: stats.shape says "D" with the spec's D2, D3, D8 and no
    targets (its other members are those of before).
No timing asserts. Python standard library only.
"""
import json
import math
import os
import random
import re
import sys
import time

import gpd

BASE = {
    "kind": "fourier-voronoi-2d",
    "seed": 11,
    "particles": 300,
    "size": {"cov": 0.5},
    "imc": {"error": "E3", "threshold": 0.05, "max_steps": 20000, "init": "halton"},
    "contour_points": 128,
}
NAMES = ("elongation", "roundness", "circularity", "regularity")
NTHETA = 128


def run_job(d, spec, timeout=300):
    jid = d.submit(spec)
    j = d.wait(jid, timeout=timeout)
    assert j["status"] == "succeeded", j
    st, _, body = d.request("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200, (st, body[:300])
    return jid, body


def without_timings(body):
    """The result's text less its "timings" object (flat: no object inside)."""
    text = body.decode()
    out, n = re.subn(r',?"timings":\{[^{}]*\}', "", text)
    assert n == 1, n
    return out


def mean_sd(v):
    m = sum(v) / len(v)
    return m, math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1))


def check_shape_common(sh, spec):
    """stats.shape members every job has (kind_fv2d.c, the top comment)."""
    for k in ("form", "spectrum", "D2", "D3", "D8", "alpha", "beta", "spread", "spread_source",
              "grains_redrawn", "grains_clipped"):
        assert k in sh, (k, sorted(sh))
    spectrum = sh["spectrum"]
    assert len(spectrum) == spec["contour_points"] // 2, len(spectrum)
    assert spectrum[0] == 1, spectrum[:4]
    assert all(isinstance(x, (int, float)) and x >= 0 for x in spectrum), spectrum
    assert sh["D2"] == spectrum[2] or sh["form"] == "D", (sh["D2"], spectrum[2])
    assert isinstance(sh["grains_redrawn"], int) and isinstance(sh["grains_clipped"], int), sh
    assert sh["grains_clipped"] == 0, sh


# ------------------------------------------------------------------ geometry of the contours

def centroid(poly):
    a = cx = cy = 0.0
    n = len(poly)
    for i in range(n):
        x0, y0 = poly[i]
        x1, y1 = poly[(i + 1) % n]
        c = x0 * y1 - x1 * y0
        a += c
        cx += (x0 + x1) * c
        cy += (y0 + y1) * c
    a *= 0.5
    return cx / (6 * a), cy / (6 * a)


def ray_distance(c, theta, poly):
    """The farthest crossing of the ray from c at angle theta with the polygon's edges (a
    star-shaped grain has one)."""
    dx, dy = math.cos(theta), math.sin(theta)
    best = None
    n = len(poly)
    for i in range(n):
        ax, ay = poly[i][0] - c[0], poly[i][1] - c[1]
        bx, by = poly[(i + 1) % n][0] - c[0], poly[(i + 1) % n][1] - c[1]
        ex, ey = bx - ax, by - ay
        den = dx * ey - dy * ex
        if den == 0:
            continue
        t = (ax * ey - ay * ex) / den  # along the ray
        u = (ax * dy - ay * dx) / den  # along the edge
        if t > 0 and -1e-12 <= u <= 1 + 1e-12 and (best is None or t > best):
            best = t
    assert best is not None, "a ray from the centroid crosses no edge"
    return best


def amplitudes(poly, nmodes=9):
    """D_0 .. D_{nmodes-1} of r(theta) about the centroid: r = r0 (1 + sum D_n cos(n theta +
    phi_n)), so D_n = 2 |C_n| / C_0 with C_n the DFT of r at NTHETA equal angles."""
    c = centroid(poly)
    r = [ray_distance(c, 2 * math.pi * j / NTHETA, poly) for j in range(NTHETA)]
    c0 = sum(r) / NTHETA
    out = [1.0]
    for n in range(1, nmodes):
        re_ = sum(r[j] * math.cos(2 * math.pi * n * j / NTHETA) for j in range(NTHETA))
        im_ = sum(r[j] * math.sin(2 * math.pi * n * j / NTHETA) for j in range(NTHETA))
        out.append(2 * math.hypot(re_, im_) / NTHETA / c0)
    return out


def d2_cov(result):
    d2 = [amplitudes(g["contour"], 3)[2] for g in result["grains"]]
    m, sd = mean_sd(d2)
    return m, sd / m


# ------------------------------------------------------------------ outlines made here

KNOWN = {2: 0.1, 3: 0.05, 4: 0.05 * (4 / 3) ** -2, 5: 0.05 * (5 / 3) ** -2, 8: 0.02}


def make_outlines(n, seed, nv=96):
    """n closed outlines of the spectrum KNOWN (random phases, sizes, positions, rotations),
    nv vertices each, counter-clockwise, not repeating the first vertex."""
    rnd = random.Random(seed)
    out = []
    for _ in range(n):
        ph = {k: rnd.uniform(0, 2 * math.pi) for k in KNOWN}
        size = rnd.uniform(0.5, 3.0)
        ox, oy = rnd.uniform(-10, 10), rnd.uniform(-10, 10)
        rot = rnd.uniform(0, 2 * math.pi)
        pts = []
        for j in range(nv):
            t = 2 * math.pi * j / nv
            r = size * (1 + sum(a * math.cos(k * t + ph[k]) for k, a in KNOWN.items()))
            pts.append([round(ox + r * math.cos(t + rot), 9), round(oy + r * math.sin(t + rot), 9)])
        out.append(pts)
    return out


# ------------------------------------------------------------------ the tests

def test_descriptors(env):
    d = env.daemon(workers=2)
    targets = {"elongation": 0.7, "circularity": 0.8}
    spec = dict(BASE, shape={"descriptors": targets}, outputs=["grains", "descriptors"])
    jid, body = run_job(d, spec)
    r = json.loads(body)
    st = r["stats"]
    grains = r["grains"]
    assert len(grains) == spec["particles"], len(grains)
    for name in NAMES:
        o = st["descriptors"][name]
        v = [g["descriptors"][name] for g in grains]
        m, sd = mean_sd(v)
        # the stored figures are the grains' own
        assert abs(o["mean"] - m) < 1e-9, (name, o["mean"], m)
        assert abs(o["sd"] - sd) < 1e-9, (name, o["sd"], sd)
        assert isinstance(o["edges"], list) and isinstance(o["achieved"], list), o
        if name in targets:
            assert o["target"] == targets[name], (name, o["target"])
            assert abs(m - targets[name]) <= 0.02, (name, m, targets[name])
            print("  %s: target %.3f, grains' mean %.4f (sd %.4f, %d grains)"
                  % (name, targets[name], m, sd, len(v)))
        else:
            assert o["target"] is None, (name, o["target"])
    sh = st["shape"]
    check_shape_common(sh, spec)
    assert sh["form"] == "descriptors", sh["form"]
    assert sh["spectrum"][0] == 1 and sh["D2"] > 0, (sh["spectrum"][:3], sh["D2"])
    assert sh["alpha"] == -2 and sh["beta"] == -2, sh
    assert sh["spread"] == 0 and sh["spread_source"] == "none" and "spread_cov" not in sh, sh
    fit = sh["fit"]
    assert set(fit) == {"predicted", "calibrated", "calibration_grains", "calibration_rounds",
                        "fit_evaluations", "missed"}, sorted(fit)
    assert fit["calibration_grains"] == spec["particles"], fit
    assert fit["calibration_rounds"] in (1, 2) and fit["fit_evaluations"] >= 1, fit
    assert fit["missed"] == [], fit
    assert set(fit["predicted"]) == set(NAMES) and set(fit["calibrated"]) == set(NAMES), fit
    assert "outlines" not in sh, sh
    assert isinstance(r["timings"].get("shape"), float) and r["timings"]["shape"] >= 0, r["timings"]
    print("  spectrum used: D2 %.4f, D3 %.4f, D8 %.4f (fit %d evaluations, %d calibration rounds)"
          % (sh["D2"], sh["D3"], sh["D8"], fit["fit_evaluations"], fit["calibration_rounds"]))
    # the summary keeps them (the views read it)
    st2, _, summ = d.json("GET", "/v1/jobs/%s/summary" % jid)
    assert st2 == 200 and summ["stats"]["descriptors"]["elongation"]["target"] == 0.7, st2
    # the descriptors view: one red target line in each panel that has a target
    st3, h, svg = d.request("GET", "/v1/jobs/%s/svg?view=descriptors" % jid)
    assert st3 == 200, (st3, svg[:300])
    svg = svg.decode()
    lines = re.findall(r'<line class="target"[^>]*>', svg)
    assert len(lines) == len(targets), lines
    assert all('stroke="#d62728"' in ln for ln in lines), lines
    # ... and none without a target
    jid0, _ = run_job(d, dict(BASE, particles=60, outputs=["grains", "descriptors"]))
    _, _, svg0 = d.request("GET", "/v1/jobs/%s/svg?view=descriptors" % jid0)
    assert b'class="target"' not in svg0, svg0[:300]
    # GET /metrics: the shape phase's durations, of the one job that had it. The worker counts
    # a job in the metrics just after its commit, which a client polling the job can see
    # first: wait (5 s at most) for the second job's count.
    count = r'grainpack_job_duration_seconds_count\{kind="fourier-voronoi-2d",phase="%s"\} (\S+)'
    deadline = time.time() + 5 * gpd.TIME_SCALE
    while True:
        st4, _, m = d.request("GET", "/metrics")
        assert st4 == 200
        m = m.decode()
        total = re.search(count % "total", m)
        if (total and float(total.group(1)) >= 2) or time.time() > deadline:
            break
        time.sleep(0.05)
    assert float(re.search(count % "shape", m).group(1)) == 1, m
    assert float(re.search(count % "total", m).group(1)) == 2, m
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def test_spread(env):
    spec = dict(BASE, shape={"spread": 0.2}, outputs=["grains"])
    d1 = env.daemon(workers=1)
    bodies = [run_job(d1, spec)[1] for _ in range(2)]
    d2 = env.daemon(workers=2, db=os.path.join(env.dir, "two.db"))
    jids = [d2.submit(spec) for _ in range(2)]  # at once, on the two workers
    for jid in jids:
        assert d2.wait(jid, timeout=300)["status"] == "succeeded"
        st, _, b = d2.request("GET", "/v1/jobs/%s/result" % jid)
        assert st == 200
        bodies.append(b)
    texts = [without_timings(b) for b in bodies]
    assert all(t == texts[0] for t in texts), [len(t) for t in texts]
    r = json.loads(bodies[0])
    sh = r["stats"]["shape"]
    check_shape_common(sh, spec)
    assert sh["form"] == "D" and sh["spread"] == 0.2 and sh["spread_source"] == "spec", sh
    cov = sh["spread_cov"]
    assert len(cov) == len(sh["spectrum"]) and cov[0] == 0 and all(c == 0.2 for c in cov[1:]), cov
    assert "shape" not in r["timings"], r["timings"]
    m, c = d2_cov(r)
    print("  spread 0.2: D2 of %d grains from their contours: mean %.4f, cov %.4f"
          % (len(r["grains"]), m, c))
    assert abs(c - 0.2) <= 0.05, c
    assert abs(m - 0.1) <= 0.02, m
    # the same measure without spread: every grain has the mean spectrum
    r0 = json.loads(run_job(d1, dict(BASE, outputs=["grains"]))[1])
    m0, c0 = d2_cov(r0)
    print("  no spread:  D2 mean %.4f, cov %.4f" % (m0, c0))
    assert c0 < 0.03, c0
    assert abs(m0 - 0.1) <= 0.01, m0
    for d in (d1, d2):
        assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def test_outlines(env):
    d = env.daemon(workers=2)
    outlines = make_outlines(20, seed=3)
    spec = dict(BASE, shape={"outlines": outlines}, outputs=["grains", "descriptors"])
    jid, body = run_job(d, spec)
    r = json.loads(body)
    st = r["stats"]
    sh = st["shape"]
    check_shape_common(sh, spec)
    assert sh["form"] == "outlines", sh["form"]
    assert sh["alpha"] is None and sh["beta"] is None, sh
    o = sh["outlines"]
    assert o["n"] == 20 and o["analysed"] == 20, o
    assert sh["spread_source"] == "outlines" and "spread_cov" in sh, sh
    for k, a in KNOWN.items():
        assert abs(sh["spectrum"][k] - a) <= 0.01, (k, sh["spectrum"][k], a)
    print("  outlines: D2 %.4f (made 0.1), D3 %.4f (0.05), D8 %.4f (0.02), spread %.4f"
          % (sh["D2"], sh["D3"], sh["D8"], sh["spread"]))
    for name in NAMES:
        od = o["descriptors"][name]
        assert st["descriptors"][name]["target"] == od["mean"], (name, od)
        assert od["sd"] >= 0, od
        m, _ = mean_sd([g["descriptors"][name] for g in r["grains"]])
        print("  %s: outlines' mean %.4f, grains' %.4f" % (name, od["mean"], m))
    assert isinstance(r["timings"].get("shape"), float), r["timings"]
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def test_default_shape(env):
    d = env.daemon(workers=2)
    spec = dict(BASE, particles=60, shape={"D2": 0.12, "D3": 0.04, "D8": 0.01},
                outputs=["grains", "descriptors"])
    _, body = run_job(d, spec)
    r = json.loads(body)
    sh = r["stats"]["shape"]
    check_shape_common(sh, spec)
    assert sh["form"] == "D" and (sh["D2"], sh["D3"], sh["D8"]) == (0.12, 0.04, 0.01), sh
    assert (sh["alpha"], sh["beta"]) == (-2, -2), sh
    assert sh["spread"] == 0 and sh["spread_source"] == "none", sh
    assert not {"spread_cov", "fit", "outlines"} & set(sh), sorted(sh)
    assert list(r["timings"]) == ["tessellation", "imc", "fill", "odec", "descriptors",
                                  "total"], r["timings"]
    for name in NAMES:
        o = r["stats"]["descriptors"][name]
        assert list(o) == ["edges", "target", "achieved", "mean", "sd"], list(o)
        assert o["target"] is None, o
    # stats keeps its members in their order, stats.shape last
    assert list(r["stats"])[-2:] == ["fit", "shape"], list(r["stats"])
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


if __name__ == "__main__":
    gpd.main([test_descriptors, test_spread, test_outlines, test_default_shape])
