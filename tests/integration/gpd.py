"""gpd.py -- helpers for the grainpackd integration tests (python3 standard library only).

Each test_*.py is run as `python3 test_x.py <path-to-grainpackd>` (ctest it_<name>). It starts
the real daemon on 127.0.0.1 port 0 with a temporary database, reads the port from the first
stdout line, and always stops its daemons (SIGTERM, then SIGKILL) before exiting.
"""
import json
import os
import select
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import traceback
import urllib.error
import urllib.request

# A small spec: quick with the real core, a few hundred milliseconds at most. The IMC
# threshold stays above the integer-count error floor even at 20 particles (0.041).
SMALL_2D = {
    "kind": "fourier-voronoi-2d",
    "seed": 42,
    "particles": 60,
    "size": {"cov": 0.5},
    "imc": {"error": "E3", "threshold": 0.05, "max_steps": 20000, "init": "halton"},
    "contour_points": 32,
    "outputs": ["grains", "odec", "descriptors", "cells"],
}

# A spec that runs for many seconds (cancel / crash tests): large, strict IMC threshold.
LONG_2D = {
    "kind": "fourier-voronoi-2d",
    "seed": 7,
    "particles": 40000,
    "imc": {"error": "E3", "threshold": 1e-9, "max_steps": 1000000000, "init": "uniform"},
    "contour_points": 64,
    "outputs": ["grains", "odec", "descriptors"],
}

# A small 3D packing: a 6 mm box of 1-2 mm spheres (a few dozen; ~1 s).
SMALL_3D = {
    "kind": "spheres-3d",
    "seed": 7,
    "box": [0.006, 0.006, 0.006],
    "sieve": [[1, 0], [2, 100]],
    "sieve_units": "mm",
    "porosity": 0.5,
    "outputs": ["spheres", "contacts", "fabric", "stress"],
}

# Latency limits are multiplied by this (set GPD_TEST_TIME_SCALE=5 for a TSan build, which
# runs the core several times slower).
TIME_SCALE = float(os.environ.get("GPD_TEST_TIME_SCALE", "1"))

VIEWS_2D = ["packing", "cells", "size", "orientation", "descriptors"]
FINAL = ("succeeded", "failed", "cancelled")
JOB_KEYS = {"id", "kind", "status", "created_at", "started_at", "finished_at", "progress", "error",
            "brief"}


class Daemon:
    """One grainpackd process on 127.0.0.1:0 (or listen="HOST:0"; requests then still go to
    127.0.0.1 when HOST is 0.0.0.0)."""

    def __init__(self, binary, db, workers=2, extra=(), env=None, tag="d", listen="127.0.0.1:0"):
        self.binary = binary
        self.listen = listen
        self.db = db
        self.workers = workers
        self.extra = list(extra)
        self.env = dict(os.environ)
        if env:
            self.env.update(env)
        self.tag = tag
        self.proc = None
        self.url = None
        self.log_path = db + "." + tag + ".log"

    def start(self, timeout=20):
        self.log = open(self.log_path, "ab")
        cmd = [self.binary, "--listen", self.listen, "--db", self.db,
               "--workers", str(self.workers)] + self.extra
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=self.log, env=self.env)
        deadline = time.time() + timeout
        line = b""
        while not line.endswith(b"\n"):
            left = deadline - time.time()
            if left <= 0 or self.proc.poll() is not None:
                self.kill9()
                raise RuntimeError("daemon did not print its address; log:\n" + self.read_log())
            r, _, _ = select.select([self.proc.stdout], [], [], left)
            if r:
                ch = os.read(self.proc.stdout.fileno(), 1)
                if not ch:
                    continue
                line += ch
        text = line.decode().strip()
        expect = "127.0.0.1:" if self.listen.startswith("127.0.0.1:") else ""
        assert text.startswith("listening on http://" + expect), text
        self.url = text[len("listening on "):].replace("//0.0.0.0:", "//127.0.0.1:")
        return self

    def read_log(self):
        try:
            with open(self.log_path, "rb") as f:
                return f.read().decode(errors="replace")[-6000:]
        except OSError:
            return ""

    def stop(self, timeout=30):
        """SIGTERM and wait; returns the exit status (0 = clean, no sanitizer report)."""
        if not self.proc or self.proc.poll() is not None:
            return self.proc.returncode if self.proc else 0
        self.proc.send_signal(signal.SIGTERM)
        try:
            rc = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill9()
            rc = -9
        self.proc.stdout.close()
        self.log.close()
        return rc

    def kill9(self):
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
            self.proc.wait(10)
        if self.proc:
            self.proc.stdout.close()
        try:
            self.log.close()
        except Exception:
            pass

    # ---- HTTP ----
    def request(self, method, path, body=None, headers=None, raw=None, timeout=30):
        """Returns (status, headers, bytes)."""
        data = raw
        hdrs = dict(headers or {})
        if body is not None:
            data = json.dumps(body).encode()
            hdrs.setdefault("Content-Type", "application/json")
        req = urllib.request.Request(self.url + path, data=data, method=method, headers=hdrs)
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                return r.status, r.headers, r.read()
        except urllib.error.HTTPError as e:
            return e.code, e.headers, e.read()

    def port(self):
        return int(self.url.rsplit(":", 1)[1])

    def raw(self, head, body_chunks=(), timeout=20):
        """Sends bytes on a raw socket (for what urllib will not send: an oversized body, a
        70 KB request line) and reads the answer until its Content-Length or the close;
        returns (status, headers with lower-case names, body)."""
        s = socket.create_connection(("127.0.0.1", self.port()), timeout=timeout)
        try:
            s.sendall(head)
            try:
                for c in body_chunks:
                    s.sendall(c)
            except (BrokenPipeError, ConnectionResetError):
                pass  # the daemon answered and closed before the whole body was sent
            data = b""
            while True:
                head_end = data.find(b"\r\n\r\n")
                if head_end >= 0:
                    lines = data[:head_end].decode("latin-1").split("\r\n")
                    hdrs = {k.lower(): v for k, v in (l.split(": ", 1) for l in lines[1:])}
                    length = hdrs.get("content-length")
                    if length is not None and len(data) >= head_end + 4 + int(length):
                        break
                chunk = s.recv(65536)
                if not chunk:
                    break
                data += chunk
        finally:
            s.close()
        head_part, _, body = data.partition(b"\r\n\r\n")
        lines = head_part.decode("latin-1").split("\r\n")
        hdrs = {k.lower(): v for k, v in (l.split(": ", 1) for l in lines[1:])}
        return int(lines[0].split(" ")[1]), hdrs, body

    def json(self, method, path, body=None, **kw):
        st, h, b = self.request(method, path, body, **kw)
        return st, h, (json.loads(b) if b else None)

    def submit(self, spec):
        st, h, j = self.json("POST", "/v1/jobs", spec)
        assert st == 201, (st, j)
        return j["id"]

    def job(self, jid):
        st, _, j = self.json("GET", "/v1/jobs/" + jid)
        assert st == 200, (st, j)
        return j

    def wait(self, jid, states=FINAL, timeout=120, interval=0.05):
        deadline = time.time() + timeout
        while True:
            j = self.job(jid)
            if j["status"] in states:
                return j
            if time.time() > deadline:
                raise AssertionError("job %s still %s after %ss" % (jid, j["status"], timeout))
            time.sleep(interval)


class Env:
    """A temp dir holding the database; cleans up daemons and files."""

    def __init__(self, binary):
        self.binary = os.path.abspath(binary)
        self.dir = tempfile.mkdtemp(prefix="gpd-it-")
        self.db = os.path.join(self.dir, "jobs.db")
        self.daemons = []

    def daemon(self, **kw):
        d = Daemon(self.binary, kw.pop("db", self.db), tag="d%d" % len(self.daemons), **kw)
        self.daemons.append(d)
        return d.start()

    def close(self, keep=False):
        for d in self.daemons:
            d.kill9()
        if not keep:
            shutil.rmtree(self.dir, ignore_errors=True)


def check_error_body(status, body, code, pointer=None):
    """Every 4xx/5xx body is {"error": {"code", "message", "pointer"?}}."""
    assert isinstance(body, dict) and set(body) == {"error"}, body
    e = body["error"]
    assert e.get("code") == code, (status, e, code)
    assert isinstance(e.get("message"), str) and e["message"], e
    if pointer is not None:
        assert e.get("pointer") == pointer, (e, pointer)


def check_job_object(j):
    assert set(j) == JOB_KEYS, sorted(j)
    assert j["status"] in ("queued", "running") + FINAL, j
    p = j["progress"]
    assert set(p) >= {"phase", "fraction", "eta_s", "detail"}, p
    assert 0.0 <= p["fraction"] <= 1.0, p
    assert j["error"] is None or set(j["error"]) >= {"code", "message"}, j
    check_brief(j["brief"])


def check_brief(b):
    """The job object's brief (README: the job's brief)."""
    assert set(b) == {"particles", "seed", "headline"}, b
    assert b["particles"] is None or (isinstance(b["particles"], int) and b["particles"] > 0), b
    assert isinstance(b["seed"], int) and b["seed"] >= 0, b
    h = b["headline"]
    assert set(h) == {"name", "target", "achieved"} and h["name"] in ("solid_fraction",
                                                                       "porosity"), b
    assert isinstance(h["target"], (int, float)), b
    assert h["achieved"] is None or isinstance(h["achieved"], (int, float)), b


def main(tests):
    """Runs test functions f(binary, env) in order; prints a summary; exit status 1 on failure."""
    if len(sys.argv) < 2:
        print("usage: %s path/to/grainpackd" % sys.argv[0])
        sys.exit(2)
    binary = sys.argv[1]
    failed = 0
    t_all = time.time()
    for t in tests:
        env = Env(binary)
        t0 = time.time()
        try:
            t(env)
            print("PASS %-40s %.2fs" % (t.__name__, time.time() - t0), flush=True)
            env.close()
        except Exception:
            failed += 1
            print("FAIL %-40s %.2fs" % (t.__name__, time.time() - t0), flush=True)
            traceback.print_exc()
            for d in env.daemons:
                print("---- daemon log %s ----\n%s" % (d.log_path, d.read_log()))
            env.close()
    print("%d passed, %d failed (%.1fs)" % (len(tests) - failed, failed, time.time() - t_all))
    sys.exit(1 if failed else 0)
