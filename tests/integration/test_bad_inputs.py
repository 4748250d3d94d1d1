"""Bad inputs get the right 4xx and the error body {"error": {"code", "message", "pointer"}}."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

TEN_MB = 10 * 1024 * 1024


def post_raw(d, raw, headers=None):
    st, h, b = d.request("POST", "/v1/jobs", raw=raw, headers=headers or {
        "Content-Type": "application/json"})
    return st, h, (json.loads(b) if b else None)


def test_spec_errors(env):
    d = env.daemon(workers=1)
    base = dict(gpd.SMALL_2D)
    sieve_2d = {k: v for k, v in base.items() if k not in ("particles", "size", "imc")}
    sieve_2d["size"] = {"law": "sieve", "sieve": [[10, 0], [20, 50], [40, 100]]}
    cases = [
        # (name, raw body, status, code, pointer)
        ("malformed", b'{"kind": "fourier-voronoi-2d", "seed": ', 400, "invalid_json", None),
        ("not json", b"hello", 400, "invalid_json", None),
        ("empty", b"", 400, "invalid_json", None),
        ("not an object", b"[1, 2]", 422, "invalid_spec", ""),
        ("wrong type", dict(base, particles="many"), 422, "invalid_spec", "/particles"),
        ("wrong nested type", dict(base, size={"cov": "x"}), 422, "invalid_spec", "/size/cov"),
        ("out of range", dict(base, particles=-5), 422, "invalid_spec", "/particles"),
        ("fraction > 1", dict(base, solid_fraction=1.5), 422, "invalid_spec", "/solid_fraction"),
        ("unknown kind", dict(base, kind="hexagons"), 422, "invalid_spec", "/kind"),
        ("missing kind", {"seed": 1}, 422, "invalid_spec", "/kind"),
        ("unknown field", dict(base, colour="red"), 422, "invalid_spec", "/colour"),
        ("unknown nested field", dict(base, imc={"error": "E3", "speed": 2}), 422,
         "invalid_spec", "/imc/speed"),
        ("bad enum", dict(base, imc={"error": "E9"}), 422, "invalid_spec", "/imc/error"),
        ("result too large", dict(base, particles=1000000, contour_points=512), 422,
         "too_large", "/particles"),
        # the same count spelled as a real is the same integer (api.md "Limits")
        ("result too large, 1e6", json.dumps(dict(base, particles="N", contour_points=512)).replace(
            '"N"', "1e6").encode(), 422, "too_large", "/particles"),
        # size laws (issue #12)
        ("cov 0", dict(base, size={"cov": 0}), 422, "invalid_spec", "/size/cov"),
        ("normal cov > 0.6", dict(base, size={"law": "normal", "cov": 0.7}), 422,
         "invalid_spec", "/size/cov"),
        ("sieve without its law", dict(base, size={"sieve": [[1, 0], [2, 100]]}), 422,
         "invalid_spec", "/size/sieve"),
        ("sieve with particles", dict(sieve_2d, particles=60), 422, "invalid_spec", "/particles"),
        ("sieve with cov", dict(sieve_2d, size=dict(sieve_2d["size"], cov=0.3)), 422,
         "invalid_spec", "/size/cov"),
        ("sieve rows", dict(sieve_2d, size=dict(sieve_2d["size"], sieve=[[20, 0], [10, 100]])),
         422, "invalid_spec", "/size/sieve/1/0"),
        # a sieve of 10-20 um grains makes ~4e9 grains in the unit square
        ("sieve count", dict(sieve_2d, size=dict(sieve_2d["size"], sieve=[[0.01, 0], [0.02, 100]])),
         422, "too_large", "/size/sieve"),
        # ~700,000 grains of 1-1.2 mm: within particles' bound, but the result is too large
        ("sieve result", dict(sieve_2d, contour_points=512, size=dict(
            sieve_2d["size"], sieve=[[1, 0], [1.2, 100]])), 422, "too_large", "/size/sieve"),
        # 3D results are bounded too: ~14M tiled spheres with their contacts (~9 GB)
        ("3D result", dict(gpd.SMALL_3D, box=[0.024] * 3, tiling=[16, 16, 16]), 422,
         "too_large", "/tiling"),
        # ... and the same bound read from a real spelling of the tiling
        ("3D result, 16.0", json.dumps(dict(gpd.SMALL_3D, box=[0.024] * 3, tiling="T")).replace(
            '"T"', "[16.0, 1.6e1, 16]").encode(), 422, "too_large", "/tiling"),
        # E3's floor at 20 cells is above 0.002: refused at submit, not failed in the queue
        ("E3 floor", dict(base, particles=20, imc={"error": "E3", "threshold": 0.002}), 422,
         "invalid_spec", "/imc/threshold"),
    ]
    for name, body, status, code, pointer in cases:
        raw = body if isinstance(body, bytes) else json.dumps(body).encode()
        st, _, j = post_raw(d, raw)
        assert st == status, (name, st, j)
        gpd.check_error_body(st, j, code, pointer)
        assert j["error"]["message"].startswith(pointer or ""), (name, j)
    st, _, j = post_raw(d, json.dumps(dict(base, particles=20, imc={"error": "E3"})).encode())
    assert "the default error AD" in j["error"]["message"], j
    # nothing was queued by any of them
    st, _, j = d.json("GET", "/v1/jobs")
    assert j["jobs"] == [], j
    assert d.stop() == 0, d.read_log()


def raw_http(d, head, body_chunks=()):
    st, _, body = d.raw(head, body_chunks)
    return st, json.loads(body)


def test_body_limit(env):
    d = env.daemon(workers=1, extra=["--max-body", "1048576"])
    # announced 10 MB body (curl does this with Expect: 100-continue): refused before reading
    head = (b"POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
            b"Content-Length: %d\r\nExpect: 100-continue\r\n\r\n" % TEN_MB)
    st, j = raw_http(d, head)
    assert st == 413, (st, j)
    gpd.check_error_body(st, j, "payload_too_large")
    # 10 MB streamed in chunks with no length: read and discarded, then 413
    head = (b"POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
            b"Transfer-Encoding: chunked\r\n\r\n")
    piece = b"x" * 65536
    chunk = b"%x\r\n" % len(piece) + piece + b"\r\n"
    chunks = [chunk] * (TEN_MB // len(piece)) + [b"0\r\n\r\n"]
    st, j = raw_http(d, head, chunks)
    assert st == 413, (st, j)
    gpd.check_error_body(st, j, "payload_too_large")
    # the daemon is still fine, and a body just under the limit is read (and rejected as JSON)
    st, _, j = post_raw(d, b" " * (1024 * 1024 - 10) + b"{")
    assert st == 400, (st, j)
    gpd.check_error_body(st, j, "invalid_json")
    assert d.stop() == 0, d.read_log()


def test_unknown_job_and_methods(env):
    d = env.daemon(workers=1)
    missing = "0123456789abcdef0123456789abcdef"
    for method, path in [("GET", "/v1/jobs/" + missing), ("DELETE", "/v1/jobs/" + missing),
                         ("GET", "/v1/jobs/%s/result" % missing),
                         ("GET", "/v1/jobs/%s/svg?view=packing" % missing),
                         ("GET", "/v1/jobs/%s/export?format=vtk" % missing),
                         ("GET", "/v1/jobs/not-a-job"), ("GET", "/v1/nothing-here")]:
        st, _, j = d.json(method, path)
        assert st == 404, (method, path, st, j)
        gpd.check_error_body(st, j, "not_found")
    for method, path, allow in [("PUT", "/v1/jobs", "POST"), ("DELETE", "/v1/jobs", "GET"),
                                ("POST", "/v1/health", "GET"), ("PATCH", "/v1/jobs/" + missing,
                                                                "DELETE"),
                                ("POST", "/v1/jobs/%s/result" % missing, "GET"),
                                ("DELETE", "/v1/schema", "GET"), ("POST", "/", "GET")]:
        st, h, j = d.json(method, path)
        assert st == 405, (method, path, st, j)
        assert allow in h.get("Allow", ""), (method, path, h.get("Allow"))
        gpd.check_error_body(st, j, "method_not_allowed")
    assert d.stop() == 0, d.read_log()


def test_not_ready_and_finished(env):
    # workers=1 and a long job first: the second job stays queued
    d = env.daemon(workers=1)
    long_id = d.submit(gpd.LONG_2D)
    jid = d.submit(gpd.SMALL_2D)
    assert d.job(jid)["status"] == "queued"
    for path in ("/result", "/svg?view=packing", "/export?format=vtk"):
        st, _, j = d.json("GET", "/v1/jobs/" + jid + path)
        assert st == 409, (path, st, j)
        gpd.check_error_body(st, j, "not_ready")
    st, _, j = d.json("GET", "/v1/jobs/%s/export?format=stl" % jid)
    assert st == 400 and "vtk" in j["error"]["message"], (st, j)
    st, _, j = d.json("DELETE", "/v1/jobs/" + long_id)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    done = d.wait(jid)
    assert done["status"] == "succeeded", done
    # DELETE of a finished job: 409; its export is now a download
    st, _, j = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 409, (st, j)
    gpd.check_error_body(st, j, "already_finished")
    st, _, j = d.json("DELETE", "/v1/jobs/" + long_id)
    assert st == 409, (st, j)
    st, h, b = d.request("GET", "/v1/jobs/%s/export?format=vtk" % jid)
    assert st == 200 and b.startswith(b"# vtk DataFile"), (st, b[:80])
    assert h.get("Content-Disposition") == 'attachment; filename="%s-vtk.vtk"' % jid, dict(h)
    assert d.stop() == 0, d.read_log()


def test_sieve_spec_stored(env):
    """A sieve-law spec is accepted and stored without an invented particles or cov; the
    threshold stored is the one of its error kind."""
    d = env.daemon(workers=1)
    long_id = d.submit(gpd.LONG_2D)  # keeps the next job queued
    spec = {"kind": "fourier-voronoi-2d", "seed": 1, "contour_points": 32,
            "size": {"law": "sieve", "sieve": [[40, 0], [60, 50], [80, 100]]}}
    jid = d.submit(spec)
    st, _, eff = d.json("GET", "/v1/jobs/%s/spec" % jid)
    assert st == 200, (st, eff)
    assert "particles" not in eff and "cov" not in eff["size"], eff
    assert eff["size"]["of"] == "grains" and eff["size"]["sieve_units"] == "mm", eff
    assert eff["imc"]["error"] == "AD" and eff["imc"]["threshold"] > 0, eff
    jid2 = d.submit(dict(gpd.SMALL_2D, imc={"error": "E2"}, particles=400))
    st, _, eff = d.json("GET", "/v1/jobs/%s/spec" % jid2)
    assert eff["imc"]["threshold"] == 0.002 and "sieve_units" not in eff["size"], eff
    for j in (long_id, jid, jid2):
        d.json("DELETE", "/v1/jobs/" + j)
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_spec_errors, test_body_limit, test_unknown_job_and_methods,
              test_not_ready_and_finished, test_sieve_spec_stored])
