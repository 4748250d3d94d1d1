"""The HTTP front under abuse and at its limits, against the real daemon: each test is a case of
the hardening list, with its figures printed.

  abandoned analyses   12 shape analyses given up by their clients after 1 s do not hold up a
                       submit (answered within 1 s: submits have their own lane of the request
                       pool) and are dropped unrun; a full lane answers 503 busy, JSON, with
                       Retry-After (test_submit_not_behind_analyses, test_pending_bound)
  slowloris            1,000 clients trickling header lines, on a daemon started under the
                       common limit of 1,024 open files: /v1/health within 1 s meanwhile, and
                       the slow connections closed at --header-timeout; one address holds at
                       most --max-connections-per-ip (test_slow_clients, test_per_ip_limit)
  lammps-relax         /v1/health within 50 ms (on a busy machine: within three times the delay
                       any stream gives the requests on its thread, the csv export's) while a
                       510,000-sphere lammps-relax archive downloads
                       (test_relax_download_keeps_health)
  error bodies         a 300 KB header, a body over a route's limit, Content-Length with
                       Transfer-Encoding (and a request pipelined after it), two lengths, an
                       unknown transfer coding: JSON errors, the ambiguous ones closed
                       (test_error_bodies_and_framing); a result's temporary file that cannot be
                       written (a file-size limit standing for a full disk) fails the job and
                       makes /v1/health degraded (test_temp_file_write_fails_health)
  outline sets         10,000 outlines of 160 points (about 30 MB) analysed, and 500 of them in a
                       job's shape.outlines, through Python's urllib and through curl; a body over
                       the limit gets a JSON 413 that urllib can read (test_outline_sets)

Localhost clients all have one address, which --max-connections-per-ip (256 by default) would
stop at 256: the slow clients connect from 127.0.0.2 to 127.0.0.11 (any 127.0.0.0/8 address is
this machine's), 100 from each, while /v1/health is asked from 127.0.0.1; test_per_ip_limit
sends 300 from one address on purpose.
"""
import contextlib
import json
import math
import os
import random
import resource
import select
import shutil
import socket
import subprocess
import sys
import tarfile
import threading
import time
import urllib.error
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

S = gpd.TIME_SCALE
ANALYZE = "/v1/shapes/analyze"


@contextlib.contextmanager
def child_limits(env, **limits):
    """Rlimits (resource name -> soft value) that the daemon started inside inherits; the test
    process gets its own back at once. The PostgreSQL server (started by the first db_url) is
    made before, so that it never runs under them."""
    env.db_url()
    old = {}
    for name, soft in limits.items():
        res = getattr(resource, "RLIMIT_" + name.upper())
        old[res] = resource.getrlimit(res)
        resource.setrlimit(res, (soft, old[res][1]))
    try:
        yield
    finally:
        for res, lim in old.items():
            resource.setrlimit(res, lim)


def health_ms(d, timeout=30):
    t0 = time.time()
    st, _, h = d.json("GET", "/v1/health", timeout=timeout)
    assert st == 200, (st, h)
    return 1e3 * (time.time() - t0), h


def full_log(d):
    with open(d.log_path, "rb") as f:
        return f.read().decode(errors="replace")


def log_count(d, text):
    return full_log(d).count(text)


# ------------------------------------------------------------------ abandoned analyses

def ring(rng, n):
    """an outline of n points: a wavy circle somewhere"""
    r0, cx, cy, k = rng.uniform(1, 2), rng.uniform(-50, 50), rng.uniform(-50, 50), rng.randint(2, 6)
    pts = []
    for i in range(n):
        t = 2 * math.pi * i / n
        r = r0 * (1 + 0.1 * math.cos(k * t))
        pts.append([round(cx + r * math.cos(t), 3), round(cy + r * math.sin(t), 3)])
    return pts


def heavy_analysis(seed):
    """A body whose analysis takes about 2 s of one core: 10,000 outlines at 256 rays (the
    analysis bound), 3 MB."""
    rng = random.Random(seed)
    return json.dumps({"outlines": [ring(rng, 16) for _ in range(10000)],
                       "contour_points": 256}).encode()


def post_and_leave(d, body, after_s):
    """A POST of body on a raw connection, closed after_s seconds later without reading."""
    s = socket.create_connection(("127.0.0.1", d.port()), timeout=30)
    s.sendall(b"POST %s HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
              b"Content-Length: %d\r\n\r\n" % (ANALYZE.encode(), len(body)) + body)
    return s, time.time() + after_s


def test_submit_not_behind_analyses(env):
    d = env.daemon(workers=1, extra=["--log-level", "debug"])
    bodies = [heavy_analysis(k) for k in range(12)]
    t0 = time.time()
    socks = [post_and_leave(d, b, 1.0) for b in bodies]
    for s, until in socks:
        time.sleep(max(0.0, until - time.time()))
        s.close()
    sent = time.time() - t0
    # a submit behind the 12 (two running, ten queued in their lane)
    t1 = time.time()
    st, _, j = d.json("POST", "/v1/jobs", gpd.SMALL_2D, timeout=60)
    submit_s = time.time() - t1
    assert st == 201, (st, j)
    ms, _ = health_ms(d)
    # the analyses nobody waits for are dropped as their turn comes, not run
    deadline = time.time() + 120 * S
    while log_count(d, "dropped, its client has gone") < 10 and time.time() < deadline:
        time.sleep(0.2)
    while log_count(d, "its client has gone") < 12 and time.time() < deadline:
        time.sleep(0.2)
    dropped = log_count(d, "dropped, its client has gone")
    stopped = log_count(d, "stopped, its client has gone")
    run = log_count(d, "http POST /v1/shapes/analyze 200")
    print("  12 analyses of %d KB posted and given up after 1 s (%.1f s); a submit behind them: "
          "201 in %.0f ms; /v1/health %.0f ms; analyses dropped unrun %d, stopped running %d, "
          "run to the end %d" % (len(bodies[0]) // 1024, sent, 1e3 * submit_s, ms, dropped,
                                 stopped, run))
    assert submit_s < 1.0 * S, submit_s
    assert dropped >= 8, d.read_log()[-3000:]
    # the ones running when their clients left stop there: none is computed to the end
    assert dropped + stopped == 12 and run == 0, d.read_log()[-3000:]
    assert d.wait(j["id"], timeout=60)["status"] == "succeeded"
    assert d.stop() == 0, d.read_log()


def test_pending_bound(env):
    # one analysis thread (two pool threads: one a lane) and one place in the queue: of five
    # analyses at once, one runs, one waits, three are refused at once
    d = env.daemon(workers=1, extra=["--http-threads", "2", "--max-pending", "1"])
    body = heavy_analysis(99)
    out = []

    def post():
        t0 = time.time()
        st, h, b = d.request("POST", ANALYZE, raw=body, timeout=120,
                             headers={"Content-Type": "application/json"})
        out.append((st, h.get("Retry-After"), b, time.time() - t0))

    threads = [threading.Thread(target=post) for _ in range(5)]
    for t in threads:
        t.start()
        time.sleep(0.3)  # in order: the first runs, the second waits
    for t in threads:
        t.join()
    busy = [o for o in out if o[0] == 503]
    ok = [o for o in out if o[0] == 200]
    print("  5 analyses at once, --max-pending 1: %d answered 200, %d refused 503 (in %s ms, "
          "Retry-After %s)" % (len(ok), len(busy), [round(1e3 * o[3]) for o in busy],
                               sorted({o[1] for o in busy})))
    assert len(ok) == 2 and len(busy) == 3, [(o[0], o[2][:100]) for o in out]
    for st, retry, b, took in busy:
        gpd.check_error_body(st, json.loads(b), "busy")
        assert retry and int(retry) >= 1, retry
        assert took < 1.0 * S, took
    # the submits' lane is another: a submit passes while analyses fill theirs
    st, _, j = d.json("POST", "/v1/jobs", gpd.SMALL_2D)
    assert st == 201, (st, j)
    assert d.stop() == 0, d.read_log()


# ------------------------------------------------------------------ slowloris

def slow_clients(d, n, addrs):
    """n connections from the addresses in turn, each sending a request line and one header;
    returns the sockets (those the daemon closed at once are closed here too: None)."""
    socks = []
    for k in range(n):
        s = socket.socket()
        s.bind((addrs[k % len(addrs)], 0))
        s.settimeout(10)
        s.connect(("127.0.0.1", d.port()))
        s.setblocking(False)
        try:
            s.send(b"GET /v1/health HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow-0: a\r\n")
        except OSError:
            pass
        socks.append(s)
    return socks


def trickle(socks, k):
    """one more header line on each open socket"""
    for s in socks:
        if s.fileno() >= 0:
            try:
                s.send(b"X-Slow-%d: a\r\n" % k)
            except OSError:
                pass


def closed(s):
    """the daemon closed s (end of stream or reset)"""
    if s.fileno() < 0:
        return True
    r, _, _ = select.select([s], [], [], 0)
    if not r:
        return False
    try:
        return s.recv(65536) == b""
    except (ConnectionResetError, BrokenPipeError):
        return True
    except BlockingIOError:
        return False


def need_files(n):
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and hard < n:
        raise gpd.Skip("the hard limit of open files is %d; this test needs %d" % (hard, n))
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, n), hard))


def test_slow_clients(env):
    need_files(2500)
    # the common default of 1,024 open files, which the daemon raises; four workers (their
    # database connections) bring its own descriptors to about 26, and a thousand clients then
    # used the rest
    with child_limits(env, nofile=1024):
        d = env.daemon(workers=4)
    addrs = ["127.0.0.%d" % k for k in range(2, 12)]
    t0 = time.time()
    socks = slow_clients(d, 1000, addrs)
    lat = []
    try:
        k = 1
        while time.time() - t0 < 6:  # well within the default --header-timeout of 10 s
            trickle(socks, k)
            k += 1
            ms, h = health_ms(d, timeout=60)
            lat.append(ms)
            time.sleep(0.5)
        alive = sum(not closed(s) for s in socks)
        # past the deadline every slow connection is closed, trickle or not
        while time.time() - t0 < 13:
            trickle(socks, k)
            k += 1
            time.sleep(1)
        gone = sum(closed(s) for s in socks)
    finally:
        for s in socks:
            s.close()
    print("  1,000 slow clients from 10 addresses (%d still open at 6 s): /v1/health x%d, "
          "slowest %.0f ms; %d closed by 13 s (--header-timeout 10)" % (
              alive, len(lat), max(lat), gone))
    assert alive >= 990, alive
    assert max(lat) < 1000 * S, lat
    assert gone >= 990, gone
    assert "open files: soft limit raised from 1024" in full_log(d), full_log(d)[:2000]
    assert "request headers took over 10 s" in full_log(d)
    assert d.stop() == 0, d.read_log()


def test_per_ip_limit(env):
    need_files(1000)
    d = env.daemon(workers=1, extra=["--max-connections-per-ip", "256"])
    socks = slow_clients(d, 300, ["127.0.0.2"])
    try:
        time.sleep(1.0)
        shut = sum(closed(s) for s in socks)
        ms, _ = health_ms(d)
    finally:
        for s in socks:
            s.close()
    print("  300 connections from 127.0.0.2, --max-connections-per-ip 256: %d closed at once; "
          "/v1/health from 127.0.0.1 in %.0f ms" % (shut, ms))
    assert shut == 300 - 256, shut
    assert ms < 1000 * S, ms
    assert d.stop() == 0, d.read_log()


# ------------------------------------------------------------------ lammps-relax

def first_body_ms(d, path, n):
    """Milliseconds from a GET of path to the first n bytes of its body (the connection is then
    dropped)."""
    s = socket.create_connection(("127.0.0.1", d.port()), timeout=60)
    t0 = time.time()
    try:
        s.sendall(b"GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n" % path.encode())
        data = b""
        while True:
            head, sep, body = data.partition(b"\r\n\r\n")
            if sep and len(body) >= n:
                break
            c = s.recv(65536)
            assert c, data[:300]
            data += c
        return 1e3 * (time.time() - t0)
    finally:
        s.close()


def polled_download(d, env, jid, fmt):
    """Downloads job jid's export in format fmt (curl, in another process: the polls here share
    no interpreter lock with it) while /v1/health is polled; (its latencies in ms, seconds,
    the file)."""
    path = os.path.join(env.dir, "export." + fmt)
    t0 = time.time()
    dl = subprocess.Popen([gpd.need("curl", "curl"), "-sS", "-o", path,
                           d.url + "/v1/jobs/%s/export?format=%s" % (jid, fmt)])
    lat = []
    while dl.poll() is None:
        ms, _ = health_ms(d)
        lat.append(ms)
        time.sleep(0.01)
    assert dl.returncode == 0, (fmt, dl.returncode)
    return lat, time.time() - t0, path


def test_relax_download_keeps_health(env):
    # one HTTP thread, which the download and /v1/health share: counting the data file on it
    # held every request for 0.8 s at this size (5.2 s at 4.2 M spheres, the tiling limit's
    # order; that job takes minutes to build, so this one is smaller). With the default pool a
    # new connection goes to a free thread; the ones already on the download's were held.
    d = env.daemon(workers=1, extra=["--http-threads", "1"])
    spec = dict(gpd.SMALL_3D, box=[0.009] * 3, tiling=[14, 14, 14], outputs=["spheres"])
    jid = d.submit(spec)
    job = d.wait(jid, timeout=600 * S)
    assert job["status"] == "succeeded", job
    spheres = job["brief"]["particles"]
    # the archive's first bytes come at once: nothing is counted at the download
    first_ms = first_body_ms(d, "/v1/jobs/%s/export?format=lammps-relax" % jid, 1024)
    # the floor: any stream on the thread delays the requests beside it a little (tens of ms
    # on a busy machine, hundreds on a very busy one); the csv export, a line per sphere and
    # no count, shows how much
    csv_lat, csv_s, _ = polled_download(d, env, jid, "csv")
    lat, took, path = polled_download(d, env, jid, "lammps-relax")
    print("  lammps-relax of %d spheres: %.1f MB in %.2f s, its first 1 KB after %.0f ms; "
          "/v1/health x%d meanwhile, slowest %.1f ms (beside the csv export: slowest %.1f ms)" % (
              spheres, os.path.getsize(path) / 1e6, took, first_ms, len(lat), max(lat),
              max(csv_lat)))
    assert spheres > 500000, spheres
    assert first_ms < 100 * S, first_ms
    # 50 ms on a quiet machine; on a loaded one within the csv stream's own delay, with room
    # for the load's swings (the count held the thread 0.7 to 1.2 s at this size)
    assert max(lat) < max(50.0, 3 * max(csv_lat), 300.0 if max(csv_lat) > 25 else 50.0) * S, (
        sorted(lat)[-5:], max(csv_lat))
    # the archive is whole: its data file as long as its header says
    with tarfile.open(path) as t:
        lines = sum(1 for _ in t.extractfile(t.getmember("lammps-relax/spheres.data")))
    assert lines > spheres, (lines, spheres)
    assert d.stop() == 0, d.read_log()


# ------------------------------------------------------------------ error bodies

def raw_exchange(d, data, wait=3.0):
    """Sends data on one connection and returns every byte the daemon sends until it closes
    (or wait seconds pass)."""
    s = socket.create_connection(("127.0.0.1", d.port()), timeout=wait)
    out = b""
    try:
        s.sendall(data)
        while True:
            c = s.recv(65536)
            if not c:
                break
            out += c
    except (socket.timeout, ConnectionResetError, BrokenPipeError):
        pass
    finally:
        s.close()
    return out


def answers(raw):
    """the (status, headers, JSON body) of each HTTP answer in raw, in order"""
    out = []
    while raw:
        head, _, rest = raw.partition(b"\r\n\r\n")
        lines = head.decode("latin-1").split("\r\n")
        h = {k.lower(): v for k, v in (l.split(": ", 1) for l in lines[1:])}
        n = int(h.get("content-length", "0"))
        out.append((int(lines[0].split(" ")[1]), h, json.loads(rest[:n]) if n else None))
        raw = rest[n:]
    return out


def test_error_bodies_and_framing(env):
    d = env.daemon(workers=1, extra=["--max-body", "1048576"])
    host = b"Host: 127.0.0.1\r\n"
    cases = [
        ("a 300 KB header", b"GET /v1/health HTTP/1.1\r\n" + host + b"X-Big: " + b"a" * 300000 +
         b"\r\n\r\n", 431, "headers_too_large"),
        ("Content-Length and chunked, a request pipelined after",
         b"POST /v1/jobs HTTP/1.1\r\n" + host + b"Content-Length: 5\r\nTransfer-Encoding: "
         b"chunked\r\n\r\n0\r\n\r\nGET /v1/health HTTP/1.1\r\n" + host + b"\r\n", 400,
         "invalid_request"),
        ("two Content-Length", b"POST /v1/jobs HTTP/1.1\r\n" + host + b"Content-Length: 2\r\n"
         b"Content-Length: 2\r\n\r\n{}", 400, "invalid_request"),
        ("Transfer-Encoding gzip", b"POST /v1/jobs HTTP/1.1\r\n" + host +
         b"Transfer-Encoding: gzip\r\n\r\n", 400, "invalid_request"),
        ("a 2 MB announced body, Expect: 100-continue", b"POST /v1/jobs HTTP/1.1\r\n" + host +
         b"Content-Length: 2097152\r\nExpect: 100-continue\r\n\r\n", 413, "payload_too_large"),
        ("a 100 KB body on a GET", b"GET /v1/health HTTP/1.1\r\n" + host +
         b"Connection: close\r\nContent-Length: 102400\r\n\r\n" + b"x" * 102400, 413,
         "payload_too_large"),
    ]
    for name, data, status, code in cases:
        got = answers(raw_exchange(d, data))
        assert got, name
        st, h, body = got[0]
        assert st == status, (name, got)
        assert h.get("content-type") == "application/json", (name, h)
        gpd.check_error_body(st, body, code)
        if status in (400, 431):  # ambiguous framing: nothing more is read on it
            assert len(got) == 1 and h.get("connection") == "close", (name, got)
        print("  %-55s %d %s" % (name, st, body["error"]["code"]))
    ms, _ = health_ms(d)
    assert ms < 1000 * S
    assert d.stop() == 0, d.read_log()


def test_temp_file_write_fails_health(env):
    # a file-size limit of 3.5 MB on the daemon: a result past the 4 MB spill threshold cannot be
    # written to its temporary file (EFBIG, as ENOSPC on a full disk) while the database's small
    # writes pass
    with child_limits(env, fsize=7 << 19):
        d = env.daemon(workers=1)
    _, _, h0 = d.json("GET", "/v1/health")
    assert h0["status"] == "ok", h0
    jid = d.submit(dict(gpd.SMALL_3D, tiling=[12, 12, 12], outputs=["spheres"]))
    job = d.wait(jid, timeout=600 * S)
    assert job["status"] == "failed" and job["error"]["code"] == "store_error", job
    assert "temporary file" in job["error"]["message"], job
    st, _, h = d.json("GET", "/v1/health")
    print("  job failed: %s; health: %s %s" % (job["error"]["message"], h["status"],
                                               json.dumps(h.get("database_error"))))
    assert st == 200 and h["status"] == "degraded" and h["database"] == "write_failed", h
    assert "temporary file" in h["database_error"]["message"], h
    assert d.stop() == 0, d.read_log()


# ------------------------------------------------------------------ outline sets

def outline_set(n, np_=160, seed=5):
    """n outlines of np_ traced points each, to 6 decimals (real outlines' precision)"""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        pts = ring(rng, np_)
        out.append([[round(x + rng.uniform(-1e-3, 1e-3), 6), round(y + rng.uniform(-1e-3, 1e-3), 6)]
                    for x, y in pts])
    return out


def urllib_post(d, path, data, timeout=300):
    req = urllib.request.Request(d.url + path, data=data, method="POST",
                                 headers={"Content-Type": "application/json"})
    t0 = time.time()
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, json.loads(r.read()), time.time() - t0
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read()), time.time() - t0


def curl_post(d, path, data, folder, timeout=300):
    f = os.path.join(folder, "body.json")
    with open(f, "wb") as fh:
        fh.write(data)
    t0 = time.time()
    r = subprocess.run([gpd.need("curl", "curl"), "-sS", "-o", "-", "-w", "\n%{http_code}",
                        "-H", "Content-Type: application/json", "--data-binary", "@" + f,
                        d.url + path], capture_output=True, timeout=timeout)
    assert r.returncode == 0, r.stderr
    body, _, code = r.stdout.rpartition(b"\n")
    return int(code), json.loads(body), time.time() - t0


def test_outline_sets(env):
    d = env.daemon(workers=1)
    outl = outline_set(10000)
    big = json.dumps({"outlines": outl}).encode()
    for name, post in (("urllib", urllib_post), ("curl", lambda *a: curl_post(*a, env.dir))):
        st, j, took = post(d, ANALYZE, big)
        assert st == 200, (name, st, str(j)[:300])
        assert j["outlines"] == 10000 and j["analysed"] == 10000, (name, j["analysed"])
        print("  10,000 outlines of 160 points (%.1f MB) analysed through %s: 200 in %.1f s" % (
            len(big) / 1e6, name, took))
    spec = dict(gpd.SMALL_2D, particles=100, shape={"outlines": outl[:500]})
    body = json.dumps(spec).encode()
    ids = []
    for name, post in (("urllib", urllib_post), ("curl", lambda *a: curl_post(*a, env.dir))):
        st, j, took = post(d, "/v1/jobs", body)
        assert st == 201, (name, st, str(j)[:300])
        ids.append(j["id"])
        print("  a job with 500 of them (%.1f MB) submitted through %s: 201 in %.2f s" % (
            len(body) / 1e6, name, took))
    for jid in ids:
        job = d.wait(jid, timeout=300 * S)
        assert job["status"] == "succeeded", job
    d.stop()
    # over the limit, sent without waiting (urllib does not send Expect: 100-continue): the
    # body is read and dropped, and the 413 is readable
    d = env.daemon(workers=1, extra=["--max-body", "1048576"])
    st, j, took = urllib_post(d, ANALYZE, big[: 3 << 20])
    gpd.check_error_body(st, j, "payload_too_large")
    assert st == 413, st
    st, j, _ = urllib_post(d, "/v1/jobs", body)
    gpd.check_error_body(st, j, "payload_too_large")
    print("  3 MB and %.1f MB over a 1 MiB --max-body through urllib: 413 payload_too_large "
          "read (%.2f s)" % (len(body) / 1e6, took))
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_error_bodies_and_framing, test_pending_bound, test_submit_not_behind_analyses,
              test_per_ip_limit, test_slow_clients, test_outline_sets,
              test_temp_file_write_fails_health, test_relax_download_keeps_health])
