"""stats.transfer of a tiled spheres-3d result (api.md: the sample and the final packing side by
side): its members as the contract lists them, the final porosity recomputed from the returned
spheres, the figures that the flip keeps (coordination with walls, PSD by number), the rdf's
largest difference and rms recomputed from its two curves, the block of tiles its final g(r) was
measured on recounted from the spheres; the summary keeps it; the "transfer" view is SVG. An
untiled job has no stats.transfer, no timings.transfer, and its "transfer" view answers 409."""
import math
import os
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

TILING = [4, 2, 2]  # more than 2 tiles along x: the final g(r) on a block of 2 x 2 x 2 tiles
SIDES = {"sample", "final"}


def cap(r, h):
    """The volume of a sphere of radius r beyond a plane at distance h < r from its centre."""
    d = r - h
    return math.pi * d * d * (3 * r - d) / 3


def tiled_porosity(spheres, sample_box, tiling):
    """1 - solid / box volume, each sphere clipped to its own tile (the tile of its centre), the
    caps beyond the tile's faces cut one face at a time (a cap across an edge of the tile is
    second order: the wall overlaps are ~1e-3 of a radius)."""
    solid = 0.0
    for x, y, z, r in spheres:
        v = 4.0 / 3.0 * math.pi * r ** 3
        for c, L, n in zip((x, y, z), sample_box, tiling):
            k = min(n - 1, max(0, int(c // L)))
            for h in (c - k * L, (k + 1) * L - c):
                if h < r:
                    v -= cap(r, h)
        solid += v
    vol = 1.0
    for L, n in zip(sample_box, tiling):
        vol *= L * n
    return 1 - solid / vol


def check_pair(o, what, scalar=True):
    assert isinstance(o, dict) and set(o) >= SIDES, (what, o)
    if scalar:
        for k in SIDES:
            assert isinstance(o[k], float) and math.isfinite(o[k]), (what, o)


def check_transfer(r, spec):
    t = r["stats"]["transfer"]
    for k in ("porosity", "coordination_number", "coordination_spheres", "fabric", "psd", "rdf",
              "max_difference"):
        assert k in t, (k, sorted(t))
    check_pair(t["porosity"], "porosity")
    check_pair(t["coordination_number"], "coordination_number")
    check_pair(t["coordination_spheres"], "coordination_spheres")
    check_pair(t["fabric"], "fabric", scalar=False)
    for k in SIDES:
        f = t["fabric"][k]
        assert len(f) == 3 and all(len(row) == 3 for row in f), f
        assert abs(f[0][0] + f[1][1] + f[2][2] - 1) < 1e-12, f
    st = r["stats"]
    # the final side is the final packing's own figures; the sample's, the sample's
    assert abs(t["porosity"]["final"] - st["porosity"]["achieved"]) < 1e-12, (t["porosity"], st)
    assert abs(t["porosity"]["sample"] - st["porosity"]["sample"]) < 1e-12, (t["porosity"], st)
    assert t["coordination_number"]["final"] == st["coordination_number"], t
    assert t["coordination_spheres"]["final"] == st["coordination_spheres"], t
    assert t["fabric"]["final"] == st["fabric"], (t["fabric"], st["fabric"])
    # the flip keeps the coordination with walls, exactly; sphere pairs grow
    assert t["coordination_number"]["sample"] == t["coordination_number"]["final"], t
    assert t["coordination_spheres"]["final"] > t["coordination_spheres"]["sample"], t
    # psd: the spec's sieves (m), by number and by weight, the flip keeping them
    psd = t["psd"]
    assert psd["diameters"] == [row[0] / 1000 for row in spec["sieve"]], psd["diameters"]
    for k in ("number", "weight"):
        check_pair(psd[k], k, scalar=False)
        for s in SIDES:
            assert len(psd[k][s]) == len(psd["diameters"]), psd
        assert psd[k]["sample"][-1] == 100.0, psd
    assert psd["number"]["sample"] == psd["number"]["final"], psd
    assert max(abs(a - b) for a, b in zip(psd["weight"]["sample"], psd["weight"]["final"])) < 1e-9
    # rdf: r in metres and in units of d50, two curves, their largest difference
    g = t["rdf"]
    for k in ("r", "r_d50", "sample", "final", "max_difference", "at_r", "rms", "measured_on"):
        assert k in g, (k, sorted(g))
    n = len(g["r"])
    assert n > 10 and len(g["r_d50"]) == n and len(g["sample"]) == n and len(g["final"]) == n, n
    d50 = g["d50"]
    assert 0.001 < d50 < 0.002, d50
    for k in range(n):
        assert abs(g["r_d50"][k] - (k + 0.5) * 0.05) < 1e-12, (k, g["r_d50"][k])
        assert abs(g["r"][k] - g["r_d50"][k] * d50) <= 1e-15, (k, g["r"][k])
    # r_max: min(5, what 3/4 of the sample box's shortest side allows)
    assert (n * 0.05 * d50 <= 0.75 * min(r["sample_box"]) < (n + 1) * 0.05 * d50) or n == 100, n
    diff = [abs(b - a) for a, b in zip(g["sample"], g["final"])]
    md = max(diff)
    assert abs(g["max_difference"] - md) < 1e-12, (g["max_difference"], md)
    k = diff.index(md)
    assert abs(g["at_r_d50"] - g["r_d50"][k]) < 1e-9 and abs(g["at_r"] - g["r"][k]) < 1e-12, g
    rms = math.sqrt(sum(x * x for x in diff) / n)
    assert abs(g["rms"] - rms) < 1e-9, (g["rms"], rms)
    assert isinstance(g["measured_on"], str) and g["measured_on"], g["measured_on"]
    m = t["max_difference"]
    for k in ("porosity", "coordination_number", "coordination_spheres", "fabric", "psd_number",
              "psd_weight", "rdf"):
        assert isinstance(m[k], float) and m[k] >= 0, (k, m)
    assert m["rdf"] == g["max_difference"] and m["coordination_number"] == 0, m
    assert m["porosity"] < 1e-12, m
    return t


def test_tiled(env):
    d = env.daemon(workers=1)
    spec = dict(gpd.SMALL_3D, tiling=TILING)
    jid = d.submit(spec)
    job = d.wait(jid, timeout=150 * gpd.TIME_SCALE)
    assert job["status"] == "succeeded", job
    st, _, r = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200, st
    t = check_transfer(r, spec)
    assert isinstance(r["timings"]["transfer"], float) and r["timings"]["transfer"] >= 0, r["timings"]
    # the final porosity, from the returned spheres
    p = tiled_porosity(r["spheres"], r["sample_box"], TILING)
    assert abs(p - t["porosity"]["final"]) < 1e-6, (p, t["porosity"])
    assert len(r["spheres"]) == r["stats"]["particles"]
    # the block of the final g(r): 2 x 2 x 2 tiles from tile (1, 0, 0), its spheres recounted
    b = t["rdf"]["block"]
    assert b["tiles"] == [2, 2, 2] and b["origin"] == [1, 0, 0], b
    sb = r["sample_box"]
    inside = sum(1 for s in r["spheres"]
                 if all(o * L <= c < (o + k) * L for c, o, k, L in zip(s, b["origin"], b["tiles"], sb)))
    assert inside == b["spheres"] == 8 * r["stats"]["sample_particles"], (inside, b)
    assert "%d of the %d spheres" % (b["spheres"], r["stats"]["particles"]) in t["rdf"]["measured_on"], t["rdf"]
    # the summary keeps stats (the dashboard's), and so stats.transfer
    st, _, summ = d.json("GET", "/v1/jobs/%s/summary" % jid)
    assert st == 200 and "spheres" not in summ and summ["stats"]["transfer"] == t, st
    # the view
    st, h, body = d.request("GET", "/v1/jobs/%s/svg?view=transfer" % jid)
    assert st == 200, (st, body[:300])
    assert h["Content-Type"].startswith("image/svg+xml"), h["Content-Type"]
    root = ET.fromstring(body)
    assert root.tag in ("{http://www.w3.org/2000/svg}svg", "svg"), root.tag
    classes = [e.get("class") for e in root.iter() if e.get("class")]
    for c in ("sample", "final", "max-difference"):
        assert c in classes, (c, classes)
    # the whole tiling (at most 2 tiles an axis): its g(r) on every sphere
    spec2 = dict(gpd.SMALL_3D, tiling=[2, 1, 2], outputs=["fabric"])
    jid2 = d.submit(spec2)
    assert d.wait(jid2, timeout=150 * gpd.TIME_SCALE)["status"] == "succeeded"
    st, _, r2 = d.json("GET", "/v1/jobs/%s/result" % jid2)
    t2 = check_transfer(r2, spec2)
    b2 = t2["rdf"]["block"]
    assert b2["tiles"] == [2, 1, 2] and b2["origin"] == [0, 0, 0], b2
    assert b2["spheres"] == r2["stats"]["particles"], (b2, r2["stats"]["particles"])
    assert t2["rdf"]["measured_on"].startswith("the whole tiling"), t2["rdf"]["measured_on"]
    # the same sample: the same sample side
    for k in ("porosity", "coordination_number", "coordination_spheres", "fabric"):
        assert t2[k]["sample"] == t[k]["sample"], k
    assert t2["rdf"]["sample"] == t["rdf"]["sample"]
    assert d.stop() == 0, d.read_log()


def test_untiled(env):
    d = env.daemon(workers=1)
    jid = d.submit(gpd.SMALL_3D)
    assert d.wait(jid, timeout=150 * gpd.TIME_SCALE)["status"] == "succeeded"
    st, _, r = d.json("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200 and r["tiling"] == [1, 1, 1], r.get("tiling")
    assert "transfer" not in r["stats"] and "transfer" not in r["timings"], r["timings"]
    st, _, j = d.json("GET", "/v1/jobs/%s/svg?view=transfer" % jid)
    assert st == 409, (st, j)
    gpd.check_error_body(st, j, "not_available")
    assert "stats.transfer" in j["error"]["message"], j
    # the other views as before
    for view in ("section", "psd"):
        st, _, body = d.request("GET", "/v1/jobs/%s/svg?view=%s" % (jid, view))
        assert st == 200, (view, st)
        ET.fromstring(body)
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_tiled, test_untiled])
