"""Origin and Host checks, the JSON 414 and the security headers (api.md, "Limits and origin").

A page on another site may not create, read or cancel jobs (403 forbidden_origin, nothing
created); a DNS-rebinding page reaches the daemon under a foreign Host name (403
forbidden_host); curl and scripts, which send no Origin, are unaffected.
"""
import base64
import hashlib
import json
import os
import re
import socket
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

EVIL = "http://evil.example"


def post(d, headers, body=None):
    raw = json.dumps(body or gpd.SMALL_2D).encode()
    st, h, b = d.request("POST", "/v1/jobs", raw=raw, headers=headers)
    return st, h, (json.loads(b) if b else None)


def jobs(d):
    st, _, j = d.json("GET", "/v1/jobs")
    assert st == 200, (st, j)
    return j["jobs"]


def test_cross_origin_refused(env):
    d = env.daemon(workers=1)
    port = d.port()
    # the CSRF of the issue: a page on another site posts text/plain (no preflight)
    for origin in (EVIL, EVIL + ":%d" % port, "null", "http://127.0.0.1:%d" % (port + 1),
                   "http://localhost", "https://evil.example", "http://127.0.0.1.evil.example:%d"
                   % port, "not an origin"):
        st, h, j = post(d, {"Origin": origin, "Content-Type": "text/plain"})
        assert st == 403, (origin, st, j)
        gpd.check_error_body(st, j, "forbidden_origin")
        assert h.get("Content-Type") == "application/json", dict(h)
        assert "Access-Control-Allow-Origin" not in h, dict(h)
    assert jobs(d) == [], "a refused POST created a job"
    # the same with a JSON content type and on the other methods
    st, _, j = post(d, {"Origin": EVIL, "Content-Type": "application/json"})
    assert st == 403, (st, j)
    assert jobs(d) == []
    jid = d.submit(gpd.LONG_2D)  # no Origin: a script
    for method, path in (("GET", "/v1/jobs"), ("GET", "/v1/jobs/" + jid),
                         ("DELETE", "/v1/jobs/" + jid), ("GET", "/v1/health"), ("GET", "/")):
        st, _, j = d.json(method, path, headers={"Origin": EVIL})
        assert st == 403, (method, path, st, j)
        gpd.check_error_body(st, j, "forbidden_origin")
    assert d.job(jid)["status"] in ("queued", "running"), "a refused DELETE cancelled the job"
    # a preflight from another site is refused too
    st, h, j = d.json("OPTIONS", "/v1/jobs", headers={
        "Origin": EVIL, "Access-Control-Request-Method": "POST"})
    assert st == 403 and "Access-Control-Allow-Origin" not in h, (st, dict(h), j)
    st, _, j = d.json("DELETE", "/v1/jobs/" + jid)
    assert st == 200 and j["status"] == "cancelled", (st, j)
    assert d.stop() == 0, d.read_log()


def test_same_origin_accepted(env):
    d = env.daemon(workers=1)
    port = d.port()
    # the dashboard's own page (as reached: Origin equals the Host it sent), and a page at
    # localhost calling 127.0.0.1 (both the daemon)
    for origin, host in ((d.url, None), ("http://localhost:%d" % port, None),
                         ("http://localhost:%d" % port, "localhost:%d" % port),
                         ("http://[::1]:%d" % port, None), ("HTTP://LocalHost:%d" % port, None)):
        hdrs = {"Origin": origin, "Content-Type": "application/json"}
        if host:
            hdrs["Host"] = host
        st, h, j = post(d, hdrs)
        assert st == 201, (origin, st, j)
        assert h.get("Access-Control-Allow-Origin") == origin, dict(h)
        st, _, j = d.json("DELETE", "/v1/jobs/" + j["id"], headers={"Origin": origin})
        assert st in (200, 409), (origin, st, j)
    # a port-forwarded daemon (docker -p 9000:PORT): the page's origin is the Host it sent
    st, _, j = post(d, {"Origin": "http://localhost:9000", "Host": "localhost:9000",
                        "Content-Type": "application/json"})
    assert st == 201, (st, j)
    assert len(jobs(d)) == 6
    # scripts: no Origin, urllib's own Host
    jid = d.submit(gpd.SMALL_2D)
    assert d.wait(jid)["status"] == "succeeded"
    st, _, _ = d.request("GET", "/v1/jobs/%s/result" % jid)
    assert st == 200
    assert d.stop() == 0, d.read_log()


def test_allow_origin(env):
    d = env.daemon(workers=1, extra=["--allow-origin", "http://lab.example:3000",
                                     "--allow-origin", "https://dash.example/, http://b.example"])
    for origin in ("http://lab.example:3000", "https://dash.example", "https://dash.example:443",
                   "http://b.example", "HTTP://LAB.EXAMPLE:3000"):
        st, h, j = post(d, {"Origin": origin, "Content-Type": "application/json"})
        assert st == 201, (origin, st, j)
        assert h.get("Access-Control-Allow-Origin") == origin, dict(h)
        assert "Location" in h.get("Access-Control-Expose-Headers", ""), dict(h)
    for origin in ("http://lab.example:3001", "http://lab.example", "https://lab.example:3000",
                   "http://dash.example", EVIL):
        st, _, j = post(d, {"Origin": origin, "Content-Type": "application/json"})
        assert st == 403, (origin, st, j)
        gpd.check_error_body(st, j, "forbidden_origin")
    # the lab dashboard's preflight (a JSON POST, a DELETE)
    for m in ("POST", "DELETE"):
        st, h, b = d.request("OPTIONS", "/v1/jobs", headers={
            "Origin": "http://lab.example:3000", "Access-Control-Request-Method": m,
            "Access-Control-Request-Headers": "content-type"})
        assert st == 204 and b == b"", (st, b)
        assert h.get("Access-Control-Allow-Origin") == "http://lab.example:3000", dict(h)
        assert m in h.get("Access-Control-Allow-Methods", ""), dict(h)
        assert "Content-Type" in h.get("Access-Control-Allow-Headers", ""), dict(h)
    assert len(jobs(d)) == 5
    assert d.stop() == 0, d.read_log()
    # the environment, comma-separated; a flag replaces it
    env_list = {"GRAINPACK_ALLOW_ORIGIN": "http://a.example:8000, http://c.example"}
    d2 = env.daemon(workers=1, db=os.path.join(env.dir, "env.db"), env=env_list)
    for origin, want in (("http://a.example:8000", 201), ("http://c.example", 201),
                         ("http://lab.example:3000", 403)):
        st, _, j = post(d2, {"Origin": origin, "Content-Type": "application/json"})
        assert st == want, (origin, st, j)
    assert d2.stop() == 0, d2.read_log()
    d3 = env.daemon(workers=1, db=os.path.join(env.dir, "env3.db"), env=env_list,
                    extra=["--allow-origin", "http://lab.example:3000"])
    for origin, want in (("http://a.example:8000", 403), ("http://lab.example:3000", 201)):
        st, _, j = post(d3, {"Origin": origin, "Content-Type": "application/json"})
        assert st == want, (origin, st, j)
    assert d3.stop() == 0, d3.read_log()
    # malformed values stop the daemon at start (exit status 2, a message); --help lists it
    for bad in ("*", "null", "lab.example:3000", "http://lab.example/path", "http://a b"):
        p = subprocess.run([env.binary, "--listen", "127.0.0.1:0", "--db",
                            os.path.join(env.dir, "bad.db"), "--allow-origin", bad],
                           capture_output=True, timeout=20)
        assert p.returncode == 2 and b"--allow-origin" in p.stderr, (bad, p.returncode, p.stderr)
    p = subprocess.run([env.binary, "--help"], capture_output=True, timeout=20)
    assert p.returncode == 0 and b"--allow-origin ORIGIN" in p.stdout, p.stdout
    assert b"GRAINPACK_ALLOW_ORIGIN" in p.stdout, p.stdout


def test_host_checked(env):
    d = env.daemon(workers=1)
    port = d.port()
    jid = d.submit(gpd.LONG_2D)
    # DNS rebinding: the page's name is in Host, whatever address it resolves to
    for host in ("evil.example", "evil.example:%d" % port, "rebind.evil.example:%d" % port,
                 "localhost.evil.example:%d" % port, "127.0.0.1.evil.example",
                 "10.1.2.3:%d" % port, "[::2]:%d" % port, "bad host", "x:y"):
        for method, path in (("GET", "/v1/jobs"), ("GET", "/v1/jobs/" + jid),
                             ("DELETE", "/v1/jobs/" + jid), ("GET", "/")):
            st, h, j = d.json(method, path, headers={"Host": host})
            assert st == 403, (host, method, path, st, j)
            gpd.check_error_body(st, j, "forbidden_host")
    st, _, j = post(d, {"Host": "evil.example:%d" % port, "Content-Type": "text/plain"})
    assert st == 403, (st, j)
    assert [x["id"] for x in jobs(d)] == [jid], "a refused POST created a job"
    assert d.job(jid)["status"] in ("queued", "running"), "a refused DELETE cancelled the job"
    # the daemon's own names, any port (port forwarding), any case, a trailing dot
    for host in ("127.0.0.1:%d" % port, "127.0.0.1", "localhost:%d" % port, "LOCALHOST",
                 "localhost.:%d" % port, "[::1]:%d" % port, "[0:0::1]", "localhost:9000"):
        st, _, j = d.json("GET", "/v1/jobs", headers={"Host": host})
        assert st == 200, (host, st, j)
    st, _, j = d.json("DELETE", "/v1/jobs/" + jid, headers={"Host": "localhost:%d" % port})
    assert st == 200 and j["status"] == "cancelled", (st, j)
    assert d.stop() == 0, d.read_log()


def test_host_wildcard(env):
    """A daemon on 0.0.0.0 answers to any IP address and to the machine's name, not to others."""
    # a sandbox may forbid the wildcard address: that (and only that) is a counted skip; a
    # daemon that fails to start where a plain socket can bind is a failure
    probe = socket.socket()
    try:
        probe.bind(("0.0.0.0", 0))
    except OSError as e:
        raise gpd.Skip("cannot listen on 0.0.0.0 here (%s)" % e)
    finally:
        probe.close()
    d = env.daemon(workers=1, listen="0.0.0.0:0")
    port = d.port()
    for host in ("192.0.2.7:%d" % port, "0.0.0.0:%d" % port, "[2001:db8::1]:%d" % port,
                 socket.gethostname().lower(), "localhost"):
        st, _, j = d.json("GET", "/v1/jobs", headers={"Host": host})
        assert st == 200, (host, st, j)
    for host in ("evil.example:%d" % port, "rebind.evil.example"):
        st, _, j = d.json("GET", "/v1/jobs", headers={"Host": host})
        assert st == 403, (host, st, j)
        gpd.check_error_body(st, j, "forbidden_host")
    # an IP Host is no licence for another origin: the page must be the one the Host names
    st, _, j = post(d, {"Host": "192.0.2.7:%d" % port, "Origin": "http://192.0.2.8:%d" % port,
                        "Content-Type": "application/json"})
    assert st == 403, (st, j)
    gpd.check_error_body(st, j, "forbidden_origin")
    st, _, j = post(d, {"Host": "192.0.2.7:%d" % port, "Origin": "http://192.0.2.7:%d" % port,
                        "Content-Type": "application/json"})
    assert st == 201, (st, j)
    assert d.stop() == 0, d.read_log()


def raw_get(d, target, extra=b""):
    """GET on a raw socket; returns (status, headers dict, body)."""
    return d.raw(b"GET " + target + b" HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n" % d.port() + extra +
                 b"Connection: close\r\n\r\n")


def test_long_url(env):
    d = env.daemon(workers=1)
    for target in (b"/" + b"a" * 70000, b"/v1/jobs?status=" + b"q" * 70000,
                   b"/v1/jobs/" + b"0" * 9000, b"/v1/health?x=" + b"1" * 160000):
        st, h, body = raw_get(d, target)
        assert st == 414, (len(target), st, body[:200])
        assert h.get("content-type") == "application/json", h
        assert h.get("x-content-type-options") == "nosniff", h
        j = json.loads(body)
        gpd.check_error_body(st, j, "uri_too_long")
        assert "8192" in j["error"]["message"], j
    # up to the limit the request is routed as usual
    st, _, body = raw_get(d, b"/v1/jobs?status=" + b"q" * (8192 - 16))
    assert st == 400, (st, body[:200])
    gpd.check_error_body(st, json.loads(body), "invalid_parameter")
    st, _, j = d.json("GET", "/v1/health")
    assert st == 200 and j["status"] == "ok", (st, j)
    assert d.stop() == 0, d.read_log()


def csp_sources(csp, directive):
    for part in csp.split(";"):
        words = part.split()
        if words and words[0] == directive:
            return words[1:]
    return None


def b64sha(text):
    return "'sha256-%s'" % base64.b64encode(hashlib.sha256(text.encode()).digest()).decode()


def test_security_headers(env):
    d = env.daemon(workers=1)
    st, h, body = d.request("GET", "/")
    # the dashboard (always built in): its page and its CSP
    assert st == 200 and h.get("Content-Type", "").startswith("text/html"), (st, dict(h))
    page = body.decode()
    csp = h.get("Content-Security-Policy", "")
    assert h.get("X-Frame-Options") == "DENY", dict(h)
    assert h.get("X-Content-Type-Options") == "nosniff", dict(h)
    assert csp_sources(csp, "default-src") == ["'self'"], csp
    assert csp_sources(csp, "frame-ancestors") == ["'none'"], csp
    assert csp_sources(csp, "object-src") == ["'none'"], csp
    # the inline script and style are allowed by hash, nothing inline beyond them
    script_src = csp_sources(csp, "script-src")
    scripts = re.findall(r"<script>(.*?)</script>", page, re.S)
    assert scripts and sorted(script_src) == sorted(b64sha(s) for s in scripts), (
        script_src, len(scripts))
    style_src = csp_sources(csp, "style-src")
    assert "'unsafe-inline'" not in style_src, csp
    for s in re.findall(r"<style>(.*?)</style>", page, re.S):
        assert b64sha(s) in style_src, (style_src, s[:80])
    attrs = re.findall(r'\sstyle="([^"]*)"', re.sub(r"<script>.*?</script>", "", page,
                                                     flags=re.S))
    for a in attrs:
        assert b64sha(a) in style_src and "'unsafe-hashes'" in style_src, (a, style_src)
    st, h, _ = d.request("HEAD", "/")
    assert st == 200 and h.get("Content-Security-Policy") == csp, dict(h)
    # every other response: nosniff, no framing, nothing runs
    jid = d.submit(gpd.SMALL_2D)
    d.wait(jid)
    for path in ("/v1/health", "/v1/jobs", "/v1/schema", "/v1/nothing", "/v1/jobs/" + jid,
                 "/v1/jobs/%s/svg?view=packing" % jid, "/v1/jobs/%s/export?format=csv" % jid,
                 "/v1/jobs/%s/result" % jid):
        st, h, _ = d.request("GET", path)
        assert st in (200, 404), (path, st)
        assert h.get("X-Content-Type-Options") == "nosniff", (path, dict(h))
        assert h.get("X-Frame-Options") == "DENY", (path, dict(h))
        csp = h.get("Content-Security-Policy", "")
        assert csp_sources(csp, "default-src") == ["'none'"], (path, csp)
        assert csp_sources(csp, "frame-ancestors") == ["'none'"], (path, csp)
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_cross_origin_refused, test_same_origin_accepted, test_allow_origin,
              test_host_checked, test_host_wildcard, test_long_url, test_security_headers])
