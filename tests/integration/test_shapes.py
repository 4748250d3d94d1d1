"""POST /v1/shapes/analyze against the real daemon (issue #17): grain outlines -> their mean
Fourier spectrum, its per-mode spread and the mean descriptors, answered at once (no job).

- round trip: 1,000 outlines drawn here from a known spectrum with a lognormal spread of 0.2
  analyse back to it (each mean D2..D8 within 10 %, the cov of D2 near 0.2);
- real outlines: the grains of a specimen grainpack made itself (a job with known D2, D3, D8
  and its own seed) analyse back to the job's spectrum; a PGM image rasterised here from a known
  spectrum, sent as {"image": ...}, is traced by the daemon and analyses back to it (as P5 with
  light grains and as P2 with dark ones, and at another pixel size: the same answer);
- hard cases, each with a clear answer: 9 / 10 / 10,000 / 10,001 outlines, more than two
  million vertices, an outline not star-shaped from any point (422 at its index, as a job submit), one
  not star-shaped from its centroid (analysed about its kernel, reported), a clockwise outline
  (reported reversed, the same spectrum as its counter-clockwise twin), duplicate points (the
  same spectrum), a triangle, three points on a line, two points, malformed JSON, other methods,
  bad images.
The generator's convention (core/2d/gp_fourier.h): r(theta) = r0 (1 + sum_n D_n cos(n theta -
delta_n)), D_0 = 1, and the spectrum of D2, D3, D8, alpha, beta of gp_fourier_spectrum."""
import base64
import json
import math
import os
import random
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

PATH = "/v1/shapes/analyze"


# ------------------------------------------------------------------ outlines made here

def spectrum(d2, d3, d8, alpha=-2.0, beta=-2.0, nmodes=64):
    """gp_fourier_spectrum: D_0 = 1, D_1 = 0, D_2, D_3, a power law to D_8, another after."""
    out = []
    for n in range(nmodes):
        out.append(1.0 if n == 0 else 0.0 if n == 1 else d2 if n == 2 else d3 if n == 3 else
                   d3 * (n / 3.0) ** alpha if n < 8 else d8 if n == 8 else
                   d8 * (n / 8.0) ** beta)
    return out


def lognormal(rng, mean, cov):
    """A draw of mean * exp(sigma z - sigma^2 / 2): mean `mean`, coefficient of variation cov
    (the schema's spread)."""
    if cov == 0:
        return mean
    s2 = math.log(1.0 + cov * cov)
    return mean * math.exp(math.sqrt(s2) * rng.gauss(0.0, 1.0) - s2 / 2.0)


def grain_radius(D, phases):
    """r(theta) / r0 as a function"""
    modes = [(n, D[n], phases[n]) for n in range(2, len(D)) if D[n] > 0]
    return lambda t: 1.0 + sum(d * math.cos(n * t - p) for n, d, p in modes)


def outline(rng, D, np_=128, spread=0.0, cw=False, digits=6):
    """One outline: the grain of spectrum D (each mode drawn with the spread), random phases,
    size, place and turn; np_ vertices (to `digits` decimals), counter-clockwise unless cw."""
    Dg = [1.0, 0.0] + [lognormal(rng, d, spread) for d in D[2:]]
    phases = [rng.uniform(-math.pi, math.pi) for _ in D]
    r = grain_radius(Dg, phases)
    r0, cx, cy = lognormal(rng, 2.0, 0.3), rng.uniform(-50, 50), rng.uniform(-50, 50)
    pts = []
    for i in range(np_):
        t = 2.0 * math.pi * i / np_
        rad = r0 * r(t)
        pts.append([round(cx + rad * math.cos(t), digits), round(cy + rad * math.sin(t), digits)])
    return pts[::-1] if cw else pts


def rel(a, b):
    return abs(a - b) / abs(b)


def analyze(d, body, timeout=120):
    return d.json("POST", PATH, body, timeout=timeout)


def stop(d):
    """a clean exit: under sanitizers, no leak or error report"""
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def check_answer(j, n, nmodes=64):
    """The answer's shape (shapes.h; api.md's fields and ours)."""
    assert {"outlines", "spectrum", "descriptors"} <= set(j), sorted(j)
    assert {"analysed", "described", "modes", "contour_points", "reversed", "pole_moved",
            "deduplicated", "no_descriptors", "refused"} <= set(j), sorted(j)
    assert j["outlines"] == n and j["modes"] == nmodes, (j["outlines"], j["modes"])
    sp = j["spectrum"]
    assert len(sp["mean"]) == nmodes and len(sp["cov"]) == nmodes and sp["mean"][0] == 1.0, sp
    for k in ("elongation", "roundness", "circularity", "regularity"):
        s = j["descriptors"][k]
        assert set(s) == {"mean", "sd"} and s["mean"] > 0 and s["sd"] >= 0, (k, s)


def near_spectrum(got, want, tol, modes=range(2, 9)):
    """[(n, relative error)] over modes; asserts each is within tol"""
    errs = [(n, rel(got[n], want[n])) for n in modes]
    bad = [(n, got[n], want[n]) for n, e in errs if e > tol]
    assert not bad, ("modes off by more than %g: " % tol, bad)
    return errs


def fmt_errs(errs):
    return " ".join("D%d %+.2f%%" % (n, 100 * e) for n, e in errs)


# ------------------------------------------------------------------ round trip

def test_round_trip_1000(env):
    d = env.daemon(workers=1)
    rng = random.Random(20261)
    D = spectrum(0.1, 0.05, 0.02)
    outl = [outline(rng, D, spread=0.2) for _ in range(1000)]
    t0 = time.time()
    st, _, j = analyze(d, {"outlines": outl})
    dt = time.time() - t0
    assert st == 200, (st, j)
    check_answer(j, 1000)
    assert j["analysed"] == 1000 and j["refused"] == [] and j["reversed"] == [], j["refused"]
    m, cov = j["spectrum"]["mean"], j["spectrum"]["cov"]
    errs = near_spectrum(m, D, 0.10)
    # the drawn spread comes back: each mode's cov near 0.2 (1,000 draws: sd of the cov ~0.005)
    assert abs(cov[2] - 0.2) < 0.03, cov[2]
    assert all(abs(cov[n] - 0.2) < 0.04 for n in range(2, 9)), cov[:9]
    assert abs(j["spectrum"]["spread"] - 0.2) < 0.04, j["spectrum"]["spread"]
    print("  round trip, 1,000 outlines in %.2f s: %s; cov D2..D8 %s" %
          (dt, fmt_errs([(n, (m[n] - D[n]) / D[n]) for n in range(2, 9)]),
           " ".join("%.3f" % c for c in cov[2:9])))
    stop(d)


# ------------------------------------------------------------------ a specimen of grainpack's own

def specimen_spec(seed, spread=None):
    shape = {"D2": 0.12, "D3": 0.06, "D8": 0.025}
    if spread is not None:
        shape["spread"] = spread
    return {"kind": "fourier-voronoi-2d", "seed": seed, "particles": 150,
            "size": {"cov": 0.4}, "shape": shape, "contour_points": 128,
            "imc": {"max_steps": 3000}, "outputs": ["grains"]}


def specimen_contours(d, spec):
    jid = d.submit(spec)
    job = d.wait(jid, timeout=300 * gpd.TIME_SCALE)
    assert job["status"] == "succeeded", job
    st, _, res = d.json("GET", "/v1/jobs/%s/result" % jid, timeout=120)
    assert st == 200, st
    return [g["contour"] for g in res["grains"]]


def test_specimen_round_trip(env):
    """The grains of a specimen grainpack made: the fill turns each grain, picks its phases
    delta_2..delta_7 and scales it to its cell, none of which changes an amplitude D_n (a ratio
    to r0, whatever the phase); so the grains analyse back to the job's D2, D3, D8 -- about the
    centroid rather than the generator's centre, which moves D_n only at second order."""
    d = env.daemon(workers=1)
    spec = specimen_spec(4611)
    D = spectrum(0.12, 0.06, 0.025)
    contours = specimen_contours(d, spec)
    assert 10 <= len(contours) <= 10000, len(contours)
    st, _, j = analyze(d, {"outlines": contours})
    assert st == 200, (st, j)
    check_answer(j, len(contours))
    m, cov = j["spectrum"]["mean"], j["spectrum"]["cov"]
    errs = near_spectrum(m, D, 0.10, modes=(2, 3, 8))
    # every grain of a spread-0 job has the same amplitudes: the set's cov is the analysis' own
    # scatter, small
    assert max(cov[2], cov[3], cov[8]) < 0.05, cov[:9]
    print("  specimen (seed 4611, %d grains, spread 0): %s; cov D2 %.4f D3 %.4f D8 %.4f; "
          "D1 %.4f" % (len(contours), fmt_errs([(n, (m[n] - D[n]) / D[n]) for n in (2, 3, 8)]),
                       cov[2], cov[3], cov[8], m[1]))
    # with a spread of 0.2 the grains' own amplitudes vary: the analysis finds it
    contours = specimen_contours(d, specimen_spec(4612, spread=0.2))
    st, _, j = analyze(d, {"outlines": contours})
    assert st == 200, (st, j)
    m, cov = j["spectrum"]["mean"], j["spectrum"]["cov"]
    near_spectrum(m, D, 0.10, modes=(2, 3, 8))
    assert 0.12 < cov[2] < 0.28, cov[:9]
    print("  specimen (seed 4612, %d grains, spread 0.2): %s; cov D2 %.3f D3 %.3f D8 %.3f" %
          (len(contours), fmt_errs([(n, (m[n] - D[n]) / D[n]) for n in (2, 3, 8)]), cov[2],
           cov[3], cov[8]))
    stop(d)


# ------------------------------------------------------------------ a traced image

def raster(rng, D, cols=6, rows=6, cell=130, r0=50.0):
    """cols x rows grains of spectrum D (random phases), ~2 r0 pixels across, one per cell of a
    grid, separated by background; rows of bytes (255 grain, 0 background), top row first"""
    w, h = cols * cell, rows * cell
    img = [bytearray(w) for _ in range(h)]
    table_n = 4096
    for gy in range(rows):
        for gx in range(cols):
            phases = [rng.uniform(-math.pi, math.pi) for _ in D]
            r = grain_radius(D, phases)
            tab = [r0 * r(2 * math.pi * k / table_n) for k in range(table_n)]
            cx = gx * cell + cell / 2 + rng.uniform(-3, 3)
            cy = gy * cell + cell / 2 + rng.uniform(-3, 3)
            rmax = max(tab)
            for y in range(int(cy - rmax) - 1, int(cy + rmax) + 2):
                row = img[y]
                dy = (y + 0.5) - cy
                for x in range(int(cx - rmax) - 1, int(cx + rmax) + 2):
                    dx = (x + 0.5) - cx
                    rr = dx * dx + dy * dy
                    if rr > rmax * rmax:
                        continue
                    k = int(round(math.atan2(-dy, dx) / (2 * math.pi) * table_n)) % table_n
                    if rr <= tab[k] * tab[k]:
                        row[x] = 255
    return w, h, img


def pgm_p5(w, h, img):
    return b"P5\n# made by test_shapes.py\n%d %d\n255\n" % (w, h) + b"".join(bytes(r) for r in img)


def pgm_p2_inverted(w, h, img):
    lines = [b"P2", b"%d %d" % (w, h), b"255"]
    for r in img:
        lines.append(b" ".join(b"0" if v else b"255" for v in r))
    return b"\n".join(lines) + b"\n"


def b64(data):
    return base64.b64encode(data).decode()


def test_image_round_trip(env):
    d = env.daemon(workers=1)
    rng = random.Random(777)
    D = spectrum(0.1, 0.05, 0.02)
    w, h, img = raster(rng, D)
    st, _, j = analyze(d, {"image": {"pgm": b64(pgm_p5(w, h, img)), "grains": "light"}})
    assert st == 200, (st, j)
    check_answer(j, 36)
    t = j["traced"]
    assert t["grains"] == 36 and t["skipped_border"] == 0 and t["skipped_small"] == 0, t
    assert (t["width"], t["height"], t["grains_are"], t["threshold"]) == (w, h, "light", 127.5), t
    assert abs(t["diameter"]["mean"] - 100) < 5, t  # 2 r0 (1 + O(D^2))
    m = j["spectrum"]["mean"]
    errs = near_spectrum(m, D, 0.10, modes=(2, 3))
    print("  image %dx%d, 36 grains of 100 px: %s; D8 %+.1f%% (the pixel staircase); "
          "refused %d" % (w, h, fmt_errs([(n, (m[n] - D[n]) / D[n]) for n in (2, 3)]),
                          100 * (m[8] - D[8]) / D[8], len(j["refused"])))
    # the same grains dark on light, as an ASCII PGM: the same outlines, the same answer
    st, _, j2 = analyze(d, {"image": {"pgm": b64(pgm_p2_inverted(w, h, img)), "grains": "dark"}})
    assert st == 200, (st, j2)
    assert j2["spectrum"] == j["spectrum"] and j2["descriptors"] == j["descriptors"], "P2 dark"
    # another pixel size scales the grains, not their shape
    st, _, j3 = analyze(d, {"image": {"pgm": b64(pgm_p5(w, h, img)), "pixel_size": 0.001,
                                      "threshold": 100}})
    assert st == 200, (st, j3)
    assert all(abs(a - b) < 1e-9 for a, b in zip(j3["spectrum"]["mean"], m)), "pixel_size"
    assert abs(j3["traced"]["diameter"]["mean"] - t["diameter"]["mean"] / 1000) < 1e-9
    stop(d)


def test_image_errors(env):
    d = env.daemon(workers=1)
    cases = [
        ({"image": {"pgm": "not base64!"}}, 422, "invalid_spec", "/image/pgm"),
        ({"image": {"pgm": b64(b"GIF89a....")}}, 422, "invalid_spec", "/image/pgm"),
        ({"image": {"pgm": b64(b"P5 5000 10 255\n")}}, 422, "too_large", "/image/pgm"),
        ({"image": {"pgm": b64(b"P5 4 4 255\n" + bytes(16))}}, 422, "invalid_spec", "/image"),
        ({"image": {"pgm": b64(b"P5 4 4 255\n" + bytes(16)), "grains": "grey"}}, 422,
         "invalid_spec", "/image/grains"),
        ({"image": {"pgm": b64(b"P5 4 4 255\n" + bytes(16)), "threshold": 300}}, 422,
         "invalid_spec", "/image/threshold"),
        ({"image": {"pgm": b64(b"P5 4 4 255\n" + bytes(16)), "pixel_size": 0}}, 422,
         "invalid_spec", "/image/pixel_size"),
        ({"image": {"grains": "dark"}}, 422, "invalid_spec", "/image/pgm"),
        ({"image": {"pgm": ""}, "outlines": []}, 422, "invalid_spec", "/image"),
        ({"image": "P5"}, 422, "invalid_spec", "/image"),
    ]
    for body, status, code, ptr in cases:
        st, _, j = analyze(d, body)
        assert st == status, (body, st, j)
        gpd.check_error_body(st, j, code, ptr)
    # an image of one grain: too few to make a spectrum, and says what it found
    rng = random.Random(5)
    w, h, img = raster(rng, spectrum(0.1, 0.05, 0.02), cols=1, rows=1)
    st, _, j = analyze(d, {"image": {"pgm": b64(pgm_p5(w, h, img))}})
    gpd.check_error_body(st, j, "invalid_spec", "/image")
    assert st == 422 and "1 grain traced" in j["error"]["message"], j
    stop(d)


# ------------------------------------------------------------------ hard cases

def set_of(n, seed, np_=128, digits=6):
    """n outlines of the spectrum's first 16 modes (quick to draw)"""
    rng = random.Random(seed)
    D = spectrum(0.1, 0.05, 0.02, nmodes=16)
    return [outline(rng, D, np_=np_, digits=digits) for _ in range(n)]


def test_counts(env):
    d = env.daemon(workers=2)
    st, _, j = analyze(d, {"outlines": set_of(9, 1)})
    gpd.check_error_body(st, j, "invalid_spec", "/outlines")
    assert st == 422 and "at least 10" in j["error"]["message"], j
    st, _, j = analyze(d, {"outlines": set_of(10, 2)})
    assert st == 200, (st, j)
    check_answer(j, 10)
    # 10,000 outlines of 64 points (the schema's most outlines; a 9 MB body)
    many = set_of(10000, 3, np_=64, digits=4)
    got, worst = {}, [0.0, 0]

    def post():
        t0 = time.time()
        got["answer"] = analyze(d, {"outlines": many}, timeout=600)
        got["dt"] = time.time() - t0

    th = threading.Thread(target=post)
    th.start()
    while th.is_alive():  # the HTTP threads stay free while it runs (offloaded): printed only
        t1 = time.time()
        assert d.json("GET", "/v1/health", timeout=60)[0] == 200
        worst = [max(worst[0], time.time() - t1), worst[1] + 1]
        time.sleep(0.05)
    th.join()
    st, _, j = got["answer"]
    dt = got["dt"]
    assert st == 200, (st, j)
    check_answer(j, 10000, nmodes=64)
    assert j["analysed"] == 10000 and j["described"] == 10000, j["analysed"]
    near_spectrum(j["spectrum"]["mean"], spectrum(0.1, 0.05, 0.02), 0.10, modes=(2, 3, 8))
    print("  10,000 outlines of 64 points: 200 in %.2f s; %d health polls meanwhile, the slowest "
          "%.0f ms" % (dt, worst[1], 1e3 * worst[0]))
    st, _, j = analyze(d, {"outlines": many + many[:1]})
    gpd.check_error_body(st, j, "invalid_spec", "/outlines")
    assert st == 422 and "at most 10000" in j["error"]["message"], j
    # over two million vertices in all: too_large, as at a submit
    fat = [[[round(math.cos(2 * math.pi * k / 201), 3), round(math.sin(2 * math.pi * k / 201), 3)]
            for k in range(201)]] * 10000
    st, _, j = analyze(d, {"outlines": fat})
    gpd.check_error_body(st, j, "too_large", "/outlines")
    assert st == 422, (st, j)
    stop(d)


def with_outline(base, i, o):
    return base[:i] + [o] + base[i + 1:]


def test_outline_cases(env):
    d = env.daemon(workers=2)
    base = set_of(12, 11)
    st, _, ref = analyze(d, {"outlines": base})
    assert st == 200, (st, ref)
    assert ref["reversed"] == [] and ref["deduplicated"] == [] and ref["pole_moved"] == []

    # a clockwise outline: reported reversed, the same spectrum as its counter-clockwise twin
    st, _, j = analyze(d, {"outlines": with_outline(base, 4, base[4][::-1])})
    assert st == 200 and j["reversed"] == [4], (st, j.get("reversed"))
    assert all(abs(a - b) <= 1e-9 * max(1.0, abs(b))
               for a, b in zip(j["spectrum"]["mean"], ref["spectrum"]["mean"])), "clockwise"

    # duplicate points (each vertex twice, and the closing point): the same spectrum
    dup = [p for p in base[7] for _ in (0, 1)] + [base[7][0]]
    st, _, j = analyze(d, {"outlines": with_outline(base, 7, dup)})
    assert st == 200 and j["deduplicated"] == [7], (st, j.get("deduplicated"))
    assert all(abs(a - b) <= 1e-9 * max(1.0, abs(b))
               for a, b in zip(j["spectrum"]["mean"], ref["spectrum"]["mean"])), "duplicates"

    # not star-shaped from any interior point (a deep U): refused at its index, as a job's
    # shape.outlines is at submit
    u = [[0, 0], [3, 0], [3, 3], [2.9, 3], [2.9, 0.1], [0.1, 0.1], [0.1, 3], [0, 3]]
    st, _, j = analyze(d, {"outlines": with_outline(base, 5, u)})
    gpd.check_error_body(st, j, "invalid_spec", "/outlines/5")
    assert st == 422 and "star" in j["error"]["message"], j
    spec = {"kind": "fourier-voronoi-2d", "shape": {"outlines": with_outline(base, 5, u)}}
    st, _, js = d.json("POST", "/v1/jobs", spec)
    gpd.check_error_body(st, js, "invalid_spec", "/shape/outlines/5")
    assert js["error"]["message"].split(": ", 1)[1] == j["error"]["message"].split(": ", 1)[1]

    # star-shaped, but not from its centroid (a square with a long spike): analysed about the
    # centroid of its kernel, reported
    spike = [[0, 0], [1, 0], [1, 0.3], [5, 0.5], [1, 0.7], [1, 1], [0, 1]]
    st, _, j = analyze(d, {"outlines": with_outline(base, 2, spike)})
    assert st == 200 and j["pole_moved"] == [2] and j["analysed"] == 12, (st, j)

    # a triangle is an outline (3 points); 3 points on a line have no area; 2 are no outline
    st, _, j = analyze(d, {"outlines": with_outline(base, 0, [[0, 0], [1, 0], [0, 1]])})
    assert st == 200 and j["analysed"] == 12 and j["refused"] == [], (st, j)
    st, _, j = analyze(d, {"outlines": with_outline(base, 9, [[0, 0], [1, 1], [2, 2]])})
    gpd.check_error_body(st, j, "invalid_spec", "/outlines/9")
    assert st == 422 and "area" in j["error"]["message"], j
    st, _, j = analyze(d, {"outlines": with_outline(base, 9, [[0, 0], [1, 1]])})
    gpd.check_error_body(st, j, "invalid_spec", "/outlines/9")
    assert st == 422 and "at least 3" in j["error"]["message"], j
    st, _, j = analyze(d, {"outlines": with_outline(base, 3, [[0, 0], [1, 0], [1, "a"]])})
    gpd.check_error_body(st, j, "invalid_spec", "/outlines/3/2/1")

    # the rays of a job with other contour_points; their work is bounded (~np^2 an outline)
    st, _, j = analyze(d, {"outlines": base, "contour_points": 64})
    assert st == 200 and j["modes"] == 32 and j["contour_points"] == 64, (st, j)
    st, _, j = analyze(d, {"outlines": base * 4, "contour_points": 4096})
    gpd.check_error_body(st, j, "too_large", "/contour_points")
    assert st == 422, (st, j)
    st, _, j = analyze(d, {"outlines": base, "contour_points": 8})
    gpd.check_error_body(st, j, "invalid_spec", "/contour_points")
    stop(d)


def test_bad_requests(env):
    d = env.daemon(workers=1)
    st, _, body = d.request("POST", PATH, raw=b'{"outlines": [[[0, 0], ', headers={
        "Content-Type": "application/json"})
    gpd.check_error_body(st, json.loads(body), "invalid_json")
    assert st == 400, st
    st, _, body = d.request("POST", PATH, raw=b"")
    gpd.check_error_body(st, json.loads(body), "invalid_json")
    assert st == 400, st
    for body, ptr in (([1, 2], ""), ({}, ""), ({"outline": []}, "/outline"),
                      ({"outlines": "x"}, "/outlines"), ({"outlines": [], "a/b": 1}, "/a~1b")):
        st, _, j = analyze(d, body)
        assert st == 422, (body, st, j)
        gpd.check_error_body(st, j, "invalid_spec", ptr)
    for method in ("GET", "PUT", "DELETE"):
        st, h, body = d.request(method, PATH)
        assert st == 405 and h["Allow"] == "POST", (method, st)
        gpd.check_error_body(st, json.loads(body), "method_not_allowed")
    # the daemon's body limit (--max-body, 128 MiB by default) holds here too: an announced
    # larger body is refused before it is sent
    head = (b"POST %s HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
            b"Content-Length: %d\r\nExpect: 100-continue\r\n\r\n" % (PATH.encode(),
                                                                         (128 << 20) + 1))
    st, _, body = d.raw(head)
    assert st == 413, st
    gpd.check_error_body(st, json.loads(body), "payload_too_large")
    stop(d)


if __name__ == "__main__":
    gpd.main([test_bad_requests, test_outline_cases, test_counts, test_round_trip_1000,
              test_specimen_round_trip, test_image_round_trip, test_image_errors])
