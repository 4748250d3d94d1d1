"""Goodness of fit of 2D specimens (issue #12 "Must show"), recomputed by the test itself.

Every statistic asserted here is computed from the returned geometry (fitcheck.py): cell areas
from the cells' polygons (shoelace), cell orientations from their convex hulls (brute-force
minimum width, not the daemon's rotating calipers), grain areas from the grains' contours, the
KS distances against CDFs written out from the laws' definitions (math.erf for the lognormal).
The daemon's own report (`stats.fit`, `warnings`) is then held to those numbers.

  test_default_counts  N = 1, 5, 20, 60, 150 with default settings: success, the cells tile the
                       container, every cell's area field is its polygons' area, a warnings list.
  test_grid            N = 500, 2000 x lognormal COV 0.1 .. 1.2 x anisotropy 1, 0.3, 0.1 (30 jobs
                       at once), default settings: area KS at most AREA_GOAL of 1.36/sqrt(N)
                       and, where Neper was run (issue #33), at most Neper's, orientation KS at
                       most ORIENT_GOAL of it, COV within 2 %, and stats.fit equal to the test's
                       figures.
  test_l_shape_and_low_cov  the same goals on an L-shaped container with a square hole; COV 0.05:
                       in the square it stops short and says in its warnings how close it came, with
                       10 or more cells' thinnest side along a wall (counted from the polygons);
                       in a 256-gon it reaches the threshold and the goals.
  test_sieve           a 2D sieve law: particles derived, percent passing by mass at 1/2/3 mm
                       within 3 points; `particles` with a sieve law is a 422 at /particles.
  test_grain_law       "of": "grains": the grain areas follow the law.
  test_imc_max_steps   imc.max_steps left out: the result's stats.imc_steps says the default
                       it used (10^6 at 3,000 grains of a law of grains, both IMC runs within
                       it; 12 x N at 90,000 cells) and the effective spec leaves it out; a
                       given one is kept, and a budget the first run uses up says so.
  test_wrong_specimen  an E3 job with 4 classes: the IMC error is small while the areas are not
                       what was asked; the fit report must say what the specimen is.
Prints a table of what was measured (N, COV, a, KS vs critical, COV error, steps, seconds).
"""
import json
import re
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fitcheck as fc  # noqa: E402
import gpd  # noqa: E402

KIND = "fourier-voronoi-2d"
UNIT_SQUARE = {"polygon": [[0, 0], [1, 0], [1, 1], [0, 1]], "holes": []}
L_SHAPE = {"polygon": [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]],
           "holes": [[[0.3, 0.3], [0.6, 0.3], [0.6, 0.6], [0.3, 0.6]]]}
COV_TOL = 0.02          # achieved COV within 2 % of the target (relative)
# The daemon's KS of the areas and its achieved mean / COV are computed from the same doubles the
# test reads back (17 significant digits), so they agree to rounding.
AGREE = 1e-9
JOB_TIMEOUT = 600 * gpd.TIME_SCALE

ROWS = []


def row(name, n, cov, a, m, steps, secs):
    ROWS.append((name, n, cov, a, m, steps, secs))


def print_table():
    if not ROWS:
        return
    print("    %-14s %5s %5s %4s %8s %8s %8s %8s %7s %7s %6s" % (
        "case", "N", "COV", "a", "KS_area", "KS_ori", "KS_crit", "COVach", "COVerr%", "steps",
        "sec"))
    for name, n, cov, a, m, steps, secs in ROWS:
        print("    %-14s %5d %5s %4s %8.4f %8s %8.4f %8.4f %7.2f %7d %6.2f" % (
            name, n, cov, a, m["ks_area"],
            "%.4f" % m["ks_orient"] if m.get("ks_orient") is not None else "-",
            m["crit"], m["cov"], 100 * m["cov_err"], steps, secs))
    da = max(r[4]["d_area"] for r in ROWS)
    do = max([r[4]["d_orient"] for r in ROWS if "d_orient" in r[4]] or [0.0])
    print("    largest |daemon - test|: area KS %.2g, orientation KS %.2g" % (da, do))
    del ROWS[:]


def spec2d(seed, n, cov=None, a=None, container=None, outputs=("cells",), **extra):
    s = {"kind": KIND, "seed": seed, "particles": n, "outputs": list(outputs)}
    if cov is not None:
        s["size"] = {"law": "lognormal", "cov": cov}
    if a is not None:
        s["orientation"] = {"mean_deg": 0, "anisotropy": a}
    if container is not None:
        s["container"] = container
    s.update(extra)
    return s


def run_all(d, specs):
    """Submits every spec at once, then polls until all are final; returns the results (each
    job must have succeeded)."""
    ids = [d.submit(s) for s in specs]
    out = []
    for jid, s in zip(ids, specs):
        job = d.wait(jid, timeout=JOB_TIMEOUT, interval=0.2)
        assert job["status"] == "succeeded", (s, job)
        st, _, body = d.request("GET", "/v1/jobs/%s/result" % jid, timeout=60)
        assert st == 200, (st, body[:300])
        out.append(json.loads(body))
    return out


def close(a, b, rel=AGREE, abs_=0.0):
    return abs(a - b) <= rel * max(abs(a), abs(b)) + abs_


def check_warnings_list(r):
    w = r.get("warnings")
    assert isinstance(w, list) and all(isinstance(x, str) and x for x in w), r.get("warnings")
    return w


def check_cells(r, n, container):
    """The cells tile the container: the polygons' areas add up to the container's area, each
    cell's area field is its polygons' area. Returns (areas, orientations, ambiguous count,
    orientation mismatches with the cells' own orientation_deg fields)."""
    cells = r["cells"]
    assert len(cells) == n, (len(cells), n)
    assert [c["id"] for c in cells] == list(range(n))
    A = fc.container_area(container)
    assert close(r["stats"]["container_area"], A, 1e-12), (r["stats"]["container_area"], A)
    areas, thetas = [], []
    amb = mism = 0
    for c in cells:
        parts = [fc.shoelace(p) for p in c["polygons"]]
        assert parts and all(p > 0 for p in parts), (c["id"], parts)  # counter-clockwise
        a = math.fsum(parts)
        assert close(c["area"], a, 1e-9, 1e-15 * A), (c["id"], c["area"], a)
        areas.append(a)
        if n > 1:
            t, ambiguous = fc.min_caliper_deg(fc.seed_part(c))
            amb += ambiguous
            if not ambiguous and fc.angle_diff_deg(t, c["orientation_deg"]) > 1e-7:
                mism += 1
            thetas.append(t)
    total = math.fsum(areas)
    assert abs(total - A) <= 1e-9 * A, ("cells do not cover the container", total, A)
    return areas, thetas, amb, mism


def check_area_fit(fit, law, values, mean_t, cov_t):
    """The daemon's area fit block against the test's own figures; returns the measures."""
    n = len(values)
    F = fc.lognormal_cdf(mean_t, cov_t)
    D = fc.ks(values, F)
    m, cov = fc.mean_cov(values)
    crit = fc.ks_critical(n)
    assert fit["law"] == law, fit
    assert fit["n"] == n, (fit["n"], n)
    assert close(fit["target"]["mean"], mean_t, 1e-12), (fit["target"], mean_t)
    assert close(fit["target"]["cov"], cov_t, 1e-12), (fit["target"], cov_t)
    assert close(fit["ks_critical"], crit, 1e-12), (fit["ks_critical"], crit)
    assert abs(fit["ks"] - D) <= AGREE, ("area KS: daemon %r, test %r" % (fit["ks"], D))
    assert close(fit["achieved"]["mean"], m), (fit["achieved"], m)
    assert close(fit["achieved"]["cov"], cov, AGREE, 1e-12), (fit["achieved"], cov)
    return {"ks_area": D, "crit": crit, "mean": m, "cov": cov, "cov_err": cov / cov_t - 1.0,
            "d_area": abs(fit["ks"] - D)}


def check_orient_fit(fit, thetas, amb, mean_deg, a):
    """Orientation KS: the test's own caliper directions against the cosine law. A cell whose
    hull has two edges of different directions with equal widths (within 1e-9) may be given
    either direction by the daemon's rotating calipers, and each such cell moves the empirical
    CDF by at most 1/n anywhere: the two KS figures may differ by amb / n, no more."""
    n = len(thetas)
    D = fc.ks(thetas, fc.cosine_cdf(mean_deg, a))
    assert fit["n"] == n, (fit["n"], n)
    assert close(fit["target"]["anisotropy"], a, 1e-12), fit
    assert fit["target"]["mean_deg"] == mean_deg, fit
    assert close(fit["ks_critical"], fc.ks_critical(n), 1e-12), fit
    tol = amb / n + AGREE
    assert abs(fit["ks"] - D) <= tol, ("orientation KS: daemon %r, test %r, %d near-tie cells"
                                       % (fit["ks"], D, amb))
    return D, abs(fit["ks"] - D)


def measure_cells(r, n, container, cov_t, a, mean_deg=0.0):
    areas, thetas, amb, mism = check_cells(r, n, container)
    fit = r["stats"]["fit"]
    A = fc.container_area(container)
    m = check_area_fit(fit["cell_area"], "lognormal", areas, A / n, cov_t)
    m["ks_orient"], m["d_orient"] = check_orient_fit(fit["cell_orientation"], thetas, amb,
                                                     mean_deg, a)
    m["amb"], m["mism"] = amb, mism
    return m


def steps_secs(r):
    return r["stats"]["imc_steps"]["achieved"], r["timings"]["total"]


# ------------------------------------------------------------------------------------- tests

def test_default_counts(env):
    d = env.daemon(workers=2)
    ns = [1, 5, 20, 60, 150]
    specs = [{"kind": KIND, "seed": 11 + n, "particles": n, "outputs": ["cells", "grains"]}
             for n in ns]
    results = run_all(d, specs)
    for n, r in zip(ns, results):
        w = check_warnings_list(r)
        areas, thetas, amb, mism = check_cells(r, n, UNIT_SQUARE)
        assert mism == 0, (n, "cells whose orientation_deg is not their min caliper", mism)
        if n == 1:
            assert w, ("one cell cannot be shaped: a warning should say so", r["warnings"])
        # grains: each area field is its contour's area; one grain per cell
        assert len(r["grains"]) == n, (n, len(r["grains"]))
        for g in r["grains"]:
            ga = abs(fc.shoelace(g["contour"]))
            assert close(g["area"], ga, 1e-9), (g["id"], g["area"], ga)
        fit = r["stats"]["fit"]
        m = check_area_fit(fit["cell_area"], "lognormal", areas, 1.0 / n, 0.5)
        if n > 1:
            m["ks_orient"], m["d_orient"] = check_orient_fit(fit["cell_orientation"], thetas,
                                                             amb, 0.0, 1.0)
        row("default", n, 0.5, 1, m, *steps_secs(r))
        if w:
            print("    N=%d warnings: %s" % (n, w))
    print_table()
    assert d.stop() == 0, d.read_log()


GRID_N = (500, 2000)
# Neper's cell-area KS at the same N and COV, isotropic (issue #33, measured on this machine
# class), and the bounds of the default specimen, as fractions of the 5 % critical value: the
# default AD threshold keeps the area KS at 0.07-0.21 of it in bench_fit2d (three seeds a case);
# one seed of the 30 here reaches 0.23 (N = 500, COV 0.8: 0.0138, where Neper has 0.010-0.012)
NEPER_KS = {(500, 0.2): 0.021, (500, 0.8): 0.010, (2000, 0.2): 0.015, (2000, 0.8): 0.005}
AREA_GOAL = 0.2
ORIENT_GOAL = 0.3
GRID_COV = (0.1, 0.2, 0.5, 0.8, 1.2)
GRID_A = (1.0, 0.3, 0.1)


def test_grid(env):
    d = env.daemon(workers=2)
    cases, specs = [], []
    for n in GRID_N:
        for cov in GRID_COV:
            for a in GRID_A:
                cases.append((n, cov, a))
                specs.append(spec2d(1000 + len(specs), n, cov, a))
    t0 = time.time()
    results = run_all(d, specs)
    wall = time.time() - t0
    bad = []
    for (n, cov, a), r in zip(cases, results):
        check_warnings_list(r)
        m = measure_cells(r, n, UNIT_SQUARE, cov, a)
        row("grid", n, cov, a, m, *steps_secs(r))
        why = []
        area_bound = AREA_GOAL * m["crit"]
        if a == 1.0 and (n, cov) in NEPER_KS:
            print("    N=%d COV=%s: area KS %.4f, Neper's %.3f" % (n, cov, m["ks_area"],
                                                                   NEPER_KS[(n, cov)]))
            area_bound = min(area_bound, NEPER_KS[(n, cov)])
        if m["ks_area"] > area_bound:
            why.append("area KS %.4f > %.4f" % (m["ks_area"], area_bound))
        if abs(m["cov_err"]) > COV_TOL:
            why.append("COV %.4f for %.4f" % (m["cov"], cov))
        if m["ks_orient"] > ORIENT_GOAL * m["crit"]:
            why.append("orientation KS %.4f > %.4f" % (m["ks_orient"], ORIENT_GOAL * m["crit"]))
        if m["mism"]:
            why.append("%d cells' orientation_deg differ from their min-caliper direction"
                       % m["mism"])
        if r["stats"]["imc_error"]["stop_reason"] == "stalled" and cov <= 0.1:
            # near-regular cells stop before the threshold once within the KS goals, and the
            # warning quotes the cells' KS: the figures this test measured from the polygons
            got = [re.search(r"within its KS goals \(areas ([0-9.]+), orientations ([0-9.]+) "
                             r"of critical\)", w) for w in r["warnings"]]
            got = [g for g in got if g]
            want = (m["ks_area"] / m["crit"], m["ks_orient"] / m["crit"])
            if len(got) != 1 or any(abs(float(g) - x) > 0.0015 for g, x in zip(got[0].groups(), want)):
                why.append("the warnings do not quote KS %.3f / %.3f: %s" % (want + (r["warnings"],)))
        if why:
            bad.append(((n, cov, a), why, r["stats"]["imc_error"], r["warnings"]))
        if m["amb"]:
            print("    N=%d COV=%s a=%s: %d near-tie cells (orientation KS daemon %.6f test %.6f)"
                  % (n, cov, a, m["amb"], r["stats"]["fit"]["cell_orientation"]["ks"],
                     m["ks_orient"]))
    print_table()
    print("    grid: %d jobs in %.1fs wall (2 workers)" % (len(specs), wall))
    assert not bad, "targets missed:\n" + "\n".join(json.dumps(b) for b in bad)
    assert d.stop() == 0, d.read_log()


def converged_or_says_so(r, m, cov_t):
    """A specimen either meets its targets or its warnings say how close it came, quoting the
    measured value of each target it missed."""
    w = check_warnings_list(r)
    missed = []
    if m["ks_area"] > m["crit"]:
        missed.append(("area KS", "%.4f" % m["ks_area"]))
    if abs(m["cov_err"]) > COV_TOL:
        missed.append(("COV", "%.3f" % m["cov"]))
    if m.get("ks_orient") is not None and m["ks_orient"] > m["crit"]:
        missed.append(("orientation KS", "%.4f" % m["ks_orient"]))
    for what, value in missed:
        assert any(value in x for x in w), (
            "%s missed (%s for a target COV %s) but no warning quotes it" % (what, value, cov_t),
            w, r["stats"]["imc_error"])
    return missed


# a 256-gon in the unit square: a container without long straight walls
POLYGON_256 = {"polygon": [[0.5 + 0.5 * math.cos(2 * math.pi * k / 256),
                            0.5 + 0.5 * math.sin(2 * math.pi * k / 256)] for k in range(256)],
               "holes": []}


def wall_ties(r):
    """Cells whose thinnest side lies along one of the unit square's walls: minimum-caliper
    direction 0 or 90 deg, from the polygons."""
    k = 0
    for c in r["cells"]:
        t, _ = fc.min_caliper_deg(fc.seed_part(c))
        k += min(abs(t), abs(abs(t) - 90.0)) < 1e-9
    return k


def test_l_shape_and_low_cov(env):
    d = env.daemon(workers=2)
    cases = [("L+hole", L_SHAPE, 0.2), ("L+hole", L_SHAPE, 0.8), ("cov0.05", UNIT_SQUARE, 0.05),
             ("cov0.05 256-gon", POLYGON_256, 0.05)]
    specs = [spec2d(2000 + i, 500, cov, 0.3, container=c) for i, (_, c, cov) in enumerate(cases)]
    results = run_all(d, specs)
    for (name, cont, cov), r in zip(cases, results):
        m = measure_cells(r, 500, cont, cov, 0.3)
        row(name, 500, cov, 0.3, m, *steps_secs(r))
        if name == "L+hole":
            multi = sum(1 for c in r["cells"] if len(c["polygons"]) > 1)
            print("    L+hole COV %s: %d multi-part cells" % (cov, multi))
            assert m["ks_area"] <= AREA_GOAL * m["crit"], m
            assert abs(m["cov_err"]) <= COV_TOL, m
            assert m["ks_orient"] <= ORIENT_GOAL * m["crit"], m
            assert m["mism"] == 0, m
        elif name == "cov0.05":
            # near-regular cells against straight walls take the walls' direction: the square
            # stops short of the threshold (stalled) with many cells tied at 0 or 90 deg ...
            missed = converged_or_says_so(r, m, cov)
            ties = wall_ties(r)
            print("    COV 0.05, square: %s; %d cells at 0 or 90 deg; imc_error %s; warnings %s" % (
                "missed " + str(missed) if missed else "KS and COV goals met", ties,
                json.dumps(r["stats"]["imc_error"]), r["warnings"]))
            assert ties >= 10, ties
            if r["stats"]["imc_error"]["stop_reason"] != "threshold":
                assert any("%d cells have their thinnest side along a straight wall" % ties in w
                           for w in r["warnings"]), (ties, r["warnings"])
        else:
            # ... while the same law in a container without long straight walls converges
            print("    COV 0.05, 256-gon: imc_error %s" % json.dumps(r["stats"]["imc_error"]))
            assert r["stats"]["imc_error"]["stop_reason"] == "threshold", r["stats"]["imc_error"]
            assert m["ks_area"] <= AREA_GOAL * m["crit"], m
            assert abs(m["cov_err"]) <= COV_TOL, m
            assert m["ks_orient"] <= ORIENT_GOAL * m["crit"], m
    print_table()
    assert d.stop() == 0, d.read_log()


SIEVE = [[0.5, 0], [1, 10], [2, 50], [3, 90], [4, 100]]


def test_sieve(env):
    d = env.daemon(workers=2)
    box = {"polygon": [[0, 0], [0.1, 0], [0.1, 0.1], [0, 0.1]], "holes": []}
    size = {"law": "sieve", "sieve": SIEVE, "sieve_units": "mm"}
    # particles with a sieve law: refused, pointing at /particles
    st, _, j = d.json("POST", "/v1/jobs", {"kind": KIND, "container": box, "size": size,
                                            "particles": 500, "outputs": ["grains"]})
    assert st == 422, (st, j)
    gpd.check_error_body(st, j, "invalid_spec", "/particles")

    spec = {"kind": KIND, "seed": 5, "container": box, "size": size, "contour_points": 32,
            "outputs": ["grains"]}
    r = run_all(d, [spec])[0]
    w = check_warnings_list(r)
    A = fc.container_area(box)
    sf = 0.65
    # the count follows from the container area, solid_fraction and the sieve's number mean
    mean_a = fc.sieve_number_mean_area(SIEVE, 1e-3)
    n_expect = sf * A / mean_a
    grains = r["grains"]
    n = len(grains)
    assert abs(n - n_expect) <= 1, ("grain count %d, container area x solid fraction / mean "
                                    "grain area = %.2f" % (n, n_expect))
    assert r["stats"]["particles"]["target"] == n == r["stats"]["particles"]["achieved"], \
        r["stats"]["particles"]
    areas = []
    for g in grains:
        ga = abs(fc.shoelace(g["contour"]))
        assert close(g["area"], ga, 1e-9), (g["id"], g["area"], ga)
        areas.append(ga)
    diam = [row_[0] * 1e-3 for row_ in SIEVE]
    got = fc.passing_by_mass(areas, diam)
    target = [row_[1] for row_ in SIEVE]
    p = r["stats"]["fit"]["passing"]
    assert all(close(a, b, 1e-12) for a, b in zip(p["diameters"], diam)), p["diameters"]
    assert p["target"] == target, p["target"]
    for k, (mine, theirs) in enumerate(zip(got, p["achieved"])):
        assert abs(mine - theirs) <= 1e-9, ("passing at %g mm: test %r, daemon %r"
                                           % (SIEVE[k][0], mine, theirs))
    err = [abs(g_ - t) for g_, t in zip(got, target)]
    assert abs(p["max_error_pp"] - max(err)) <= 1e-9, (p["max_error_pp"], err)
    for k in (1, 2, 3):  # 1, 2, 3 mm
        assert err[k] <= 3.0, ("passing at %g mm: %.2f %% for %g %%" % (SIEVE[k][0], got[k],
                                                                      target[k]))
    print("    sieve: %d grains (expected %.1f), passing %s for %s (max error %.2f pp), "
          "%d steps, %.1fs; warnings %s" % (n, n_expect, ["%.2f" % x for x in got], target,
                                            max(err), r["stats"]["imc_steps"]["achieved"],
                                            r["timings"]["total"], w))
    assert d.stop() == 0, d.read_log()


def test_grain_law(env):
    d = env.daemon(workers=2)
    n, cov, sf = 500, 0.5, 0.65
    spec = {"kind": KIND, "seed": 21, "particles": n, "contour_points": 64,
            "size": {"law": "lognormal", "cov": cov, "of": "grains"}, "outputs": ["grains"]}
    r = run_all(d, [spec])[0]
    check_warnings_list(r)
    grains = r["grains"]
    assert len(grains) == n, len(grains)
    areas = []
    for g in grains:
        ga = abs(fc.shoelace(g["contour"]))
        assert close(g["area"], ga, 1e-9), (g["id"], g["area"], ga)
        areas.append(ga)
    m = check_area_fit(r["stats"]["fit"]["grain_area"], "lognormal", areas, sf * 1.0 / n, cov)
    row("of=grains", n, cov, 1, m, *steps_secs(r))
    print_table()
    assert m["ks_area"] <= m["crit"], ("grain-area KS %.4f above %.4f" % (m["ks_area"], m["crit"]),
                                       r["warnings"])
    assert d.stop() == 0, d.read_log()


def summary_of(d, spec):
    jid = d.submit(spec)
    job = d.wait(jid, timeout=JOB_TIMEOUT, interval=0.2)
    assert job["status"] == "succeeded", (spec, job)
    st, _, body = d.request("GET", "/v1/jobs/%s/summary" % jid, timeout=60)
    assert st == 200, (st, body[:300])
    st, _, eff = d.json("GET", "/v1/jobs/%s/spec" % jid)
    assert st == 200, (st, eff)
    return json.loads(body), eff


def test_imc_max_steps(env):
    d = env.daemon(workers=2)
    n = 3000
    grains = {"kind": KIND, "seed": 21, "particles": n, "contour_points": 32,
              "size": {"cov": 0.5, "of": "grains"}, "outputs": ["grains"]}
    r = run_all(d, [grains])[0]
    st = r["stats"]["imc_steps"]
    print("    of=grains, N %d, max_steps left out: %s" % (n, st))
    # the default for 3,000 cells, both runs (cells, then resized for their grains) within it
    assert st["max"] == 1000000 and st["default"] is True, st
    assert len(st["runs"]) == 2 and all(k > 0 for k in st["runs"]), st
    assert sum(st["runs"]) == st["achieved"] <= st["max"], st
    areas = [abs(fc.shoelace(g["contour"])) for g in r["grains"]]
    m = check_area_fit(r["stats"]["fit"]["grain_area"], "lognormal", areas, 0.65 / n, 0.5)
    assert m["ks_area"] <= 0.5 * m["crit"], (m["ks_area"], m["crit"])
    assert not [w for w in r["warnings"] if "not resized" in w], r["warnings"]

    # a given budget is the user's: kept, and the first run using it up says so
    given = dict(grains, imc={"max_steps": 5000})
    r = run_all(d, [given])[0]
    st = r["stats"]["imc_steps"]
    print("    of=grains, N %d, max_steps 5000: %s" % (n, st))
    assert st == {"max": 5000, "achieved": 5000, "default": False, "runs": [5000]}, st
    said = [w for w in r["warnings"] if "not resized" in w]
    assert len(said) == 1 and "(5000)" in said[0], r["warnings"]

    # beyond 83,333 cells the default grows with N: 12 moves a cell
    big = 90000
    summary, eff = summary_of(d, {"kind": KIND, "seed": 3, "particles": big,
                                  "outputs": ["cells"]})
    st = summary["stats"]["imc_steps"]
    print("    cells, N %d, max_steps left out: %s, stop %s" % (
        big, st, summary["stats"]["imc_error"]["stop_reason"]))
    assert st["max"] == 12 * big and st["default"] is True, st
    assert st["runs"] == [st["achieved"]] and 0 < st["achieved"] <= st["max"], st
    assert "max_steps" not in eff.get("imc", {}), eff  # the effective spec leaves it out
    assert d.stop() == 0, d.read_log()


def test_wrong_specimen(env):
    """E3 with 4 classes: a histogram of few classes can be matched by the wrong law. Whatever
    the specimen is, the fit report must be what the test measures on it, not the IMC's view."""
    d = env.daemon(workers=2)
    n, cov, thr = 500, 0.2, 0.05
    spec = spec2d(31, n, cov, 1.0, imc={"error": "E3", "threshold": thr, "classes": 4})
    st, _, j = d.json("POST", "/v1/jobs", spec)
    assert st == 201, (st, j)
    job = d.wait(j["id"], timeout=JOB_TIMEOUT, interval=0.2)
    assert job["status"] == "succeeded", job
    r = d.json("GET", "/v1/jobs/%s/result" % j["id"])[2]
    ie = r["stats"]["imc_error"]
    assert ie["measure"] == "E3", ie
    m = measure_cells(r, n, UNIT_SQUARE, cov, 1.0)
    row("E3 4 classes", n, cov, 1, m, *steps_secs(r))
    print_table()
    print("    E3 specimen: imc_error %s; test: area KS %.4f (crit %.4f), COV %.4f for %.2f; "
          "warnings %s" % (json.dumps(ie), m["ks_area"], m["crit"], m["cov"], cov, r["warnings"]))
    # the IMC's own view: its error is at or under the threshold (it stopped there) ...
    assert ie["achieved"] <= thr, ie
    # ... and the fit says what the cells are (check_area_fit held ks / mean / cov to the test's
    # figures); a miss is a warning that quotes it
    converged_or_says_so(r, m, cov)
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_default_counts, test_grid, test_l_shape_and_low_cov, test_sieve,
              test_grain_law, test_imc_max_steps, test_wrong_specimen])
