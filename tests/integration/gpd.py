"""gpd.py -- helpers for the grainpackd integration tests (python3 standard library only).

Each test_*.py is run as `python3 test_x.py <path-to-grainpackd>` (ctest it_<name>). It starts
the real daemon on 127.0.0.1 port 0 with a temporary database, reads the port from the first
stdout line, and always stops its daemons (SIGTERM, then SIGKILL) before exiting.

Back ends: by default the database is an SQLite file in the test's temporary directory. With
GP_TEST_DB=postgresql (ctest it_pg_<name>) the same tests run against PostgreSQL: the first
daemon of the process starts a real server of its own (PgServer: Debian's initdb + pg_ctl in a
temporary directory, 127.0.0.1 on a free port, trust authentication, fsync off; as root it runs
as user postgres), every database path a test names becomes a fresh database on it (CREATE
DATABASE, one per path per test), and the daemon gets its postgresql:// URL. The server is
stopped and removed at exit, also after a failure. A test meaningless there (the SQLite file's
lock, size or page limit) is listed in PG_SKIP and skipped with its reason.

Skips: the only ways a test is skipped are PG_SKIP (above) and `raise gpd.Skip(reason)` from
the test itself, for a condition of the machine the test cannot change (never for a missing
program: need() fails instead). main() prints "SKIP <name> <reason>" for each and counts them in
its last line, "N passed, N failed, N skipped"; a test that only prints that it skipped would be
counted as passed.
"""
import atexit
import glob
import json
import os
import pwd
import re
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

# Latency limits are multiplied by this (tests/run.sh sets GPD_TEST_TIME_SCALE=2 for its ASan
# pass; set 5 for a TSan build, which runs the core several times slower).
TIME_SCALE = float(os.environ.get("GPD_TEST_TIME_SCALE", "1"))

# How long one run of a program the exports are loaded into (LAMMPS, YADE, ...) may take.
PROGRAM_TIMEOUT = 300 * TIME_SCALE

DB_MODE = os.environ.get("GP_TEST_DB", "sqlite")
PG = DB_MODE == "postgresql"

# Tests that test SQLite itself and have no meaning on PostgreSQL: name -> why (printed).
PG_SKIP = {
    "test_second_daemon_refused": "the SQLite file lock; on PostgreSQL many daemons share a "
                                  "queue by design (test_pg_cluster)",
    "test_disk_full_fails_visibly": "SQLite's page cap (a testing hook) stands for a full disk",
    "test_purge_gives_space_back": "it measures the SQLite file and its WAL on disk",
    "test_database_before_briefs": "it migrates an SQLite file made by an older grainpackd",
}


def pg_bindir():
    """The directory of initdb/pg_ctl/psql: pg_config's, else the newest Debian version."""
    try:
        d = subprocess.run(["pg_config", "--bindir"], capture_output=True, text=True,
                           timeout=10).stdout.strip()
        if d and os.path.exists(os.path.join(d, "initdb")):
            return d
    except OSError:
        pass
    found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"),
                   key=lambda p: int(p.split("/")[4]) if p.split("/")[4].isdigit() else 0)
    if not found:
        raise RuntimeError("PostgreSQL's initdb not found (apt-get install postgresql)")
    return os.path.dirname(found[-1])


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class PgServer:
    """A PostgreSQL server of the tests' own: start(), url(db), create_db(name), psql(sql),
    stop() (also at exit)."""

    def __init__(self, durable=False, max_connections=400):
        self.durable = durable  # fsync on (benchmarks next to SQLite's synchronous=FULL)
        self.max_connections = max_connections  # the clients the server serves at once
        self.bindir = pg_bindir()
        self.dir = tempfile.mkdtemp(prefix="gpd-pg-")
        self.data = os.path.join(self.dir, "data")
        self.port = None
        self.user = None  # run the server's programs as this user (root: postgres)
        self.count = 0

    def _cmd(self, args, **kw):
        cmd = [os.path.join(self.bindir, args[0])] + list(args[1:])
        if self.user:
            cmd = ["runuser", "-u", self.user, "--"] + cmd
        kw.setdefault("timeout", 120)
        return subprocess.run(cmd, capture_output=True, text=True, **kw)

    def start(self):
        if os.geteuid() == 0:  # initdb refuses root
            self.user = "postgres"
            pw = pwd.getpwnam(self.user)
            os.chown(self.dir, pw.pw_uid, pw.pw_gid)
        r = self._cmd(["initdb", "-D", self.data, "-U", "postgres", "-A", "trust", "-E", "UTF8",
                       "--locale=C", "--no-sync"])
        if r.returncode == 0 and self.durable:
            os.sync()
        if r.returncode:
            raise RuntimeError("initdb failed:\n" + r.stdout + r.stderr)
        for attempt in range(5):  # the free port may be taken between its choice and the bind
            self.port = free_port()
            r = self._pg_ctl_start()
            if r.returncode == 0:
                atexit.register(self.stop)
                return self
        raise RuntimeError("pg_ctl start failed:\n" + r.stdout + r.stderr + self.log())

    def _pg_ctl_start(self):
        opts = ("-c listen_addresses=127.0.0.1 -p %d -k %s -c max_connections=%d"
                % (self.port, self.dir, self.max_connections))
        if not self.durable:  # tests: the server's data is thrown away anyway
            opts += " -c fsync=off -c synchronous_commit=off -c full_page_writes=off"
        return self._cmd(["pg_ctl", "-D", self.data, "-o", opts, "-l",
                          os.path.join(self.dir, "server.log"), "-w", "-t", "60", "start"])

    def halt(self):
        """Stops the server as an administrator's restart does (pg_ctl -m fast: every
        connection closed by the server), keeping its data and port for resume()."""
        r = self._cmd(["pg_ctl", "-D", self.data, "-m", "fast", "-w", "stop"], timeout=60)
        if r.returncode:
            raise RuntimeError("pg_ctl stop failed:\n" + r.stdout + r.stderr)

    def resume(self):
        """Starts the server halt() stopped, on the same port."""
        r = self._pg_ctl_start()
        if r.returncode:
            raise RuntimeError("pg_ctl start failed:\n" + r.stdout + r.stderr + self.log())

    def log(self):
        try:
            with open(os.path.join(self.dir, "server.log")) as f:
                return f.read()[-4000:]
        except OSError:
            return ""

    def url(self, db):
        return "postgresql://postgres@127.0.0.1:%d/%s" % (self.port, db)

    def psql(self, sql, db="postgres", variables=None):
        """Runs sql (from stdin, so that :'name' quotes the value of variables[name]); returns
        the rows as text (unaligned, tuples only)."""
        cmd = [os.path.join(self.bindir, "psql"), "-X", "-q", "-At", "-v", "ON_ERROR_STOP=1",
               "-h", "127.0.0.1", "-p", str(self.port), "-U", "postgres", "-d", db]
        for k, v in (variables or {}).items():
            cmd += ["-v", "%s=%s" % (k, v)]
        r = subprocess.run(cmd, input=sql, capture_output=True, text=True, timeout=60)
        if r.returncode:
            raise RuntimeError("psql failed: %s\n%s" % (sql, r.stderr))
        return r.stdout

    def create_db(self, prefix="gp"):
        self.count += 1
        name = "%s_%d_%d" % (prefix, os.getpid(), self.count)
        self.psql("CREATE DATABASE %s" % name)  # a name made here: no user data
        return name

    def stop(self):
        if self.port and os.path.isdir(self.data):
            self._cmd(["pg_ctl", "-D", self.data, "-m", "immediate", "-w", "stop"], timeout=60)
        shutil.rmtree(self.dir, ignore_errors=True)
        self.port = None


_pg = None


def pg_server():
    """The process's PostgreSQL server, started on first use."""
    global _pg
    if _pg is None:
        _pg = PgServer().start()
    return _pg


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
        self.db_arg = db  # what --db gets: the path, or (GP_TEST_DB=postgresql) a URL

    def start(self, timeout=20):
        self.log = open(self.log_path, "ab")
        cmd = [self.binary, "--listen", self.listen, "--db", self.db_arg,
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
    """A temp dir holding the database; cleans up daemons and files. On PostgreSQL each
    database path stands for a database of its own on the process's server."""

    def __init__(self, binary):
        self.binary = os.path.abspath(binary)
        self.dir = tempfile.mkdtemp(prefix="gpd-it-")
        self.db = os.path.join(self.dir, "jobs.db")
        self.daemons = []
        self.pg_dbs = {}  # path -> database name

    def db_url(self, path=None):
        """The --db value for a database path: the path, or its PostgreSQL URL."""
        path = path or self.db
        if not PG:
            return path
        if path not in self.pg_dbs:
            self.pg_dbs[path] = pg_server().create_db()
        return pg_server().url(self.pg_dbs[path])

    def daemon(self, **kw):
        path = kw.pop("db", self.db)
        d = Daemon(self.binary, path, tag="d%d" % len(self.daemons), **kw)
        d.db_arg = self.db_url(path)
        self.daemons.append(d)
        return d.start()

    def execute(self, sql, params=(), path=None):
        """Runs one statement on the jobs database with ? placeholders (test set-up, e.g.
        backdating jobs): sqlite3 on the file, psql on PostgreSQL."""
        if not PG:
            import sqlite3
            con = sqlite3.connect(path or self.db)
            con.execute(sql, params)
            con.commit()
            con.close()
            return None
        parts = sql.split("?")
        assert len(parts) == len(params) + 1, sql
        text = parts[0] + "".join(":'p%d'%s" % (i, p) for i, p in enumerate(parts[1:]))
        self.db_url(path)
        return pg_server().psql(text + ";\n", self.pg_dbs[path or self.db],
                                {"p%d" % i: v for i, v in enumerate(params)})

    def query_int(self, sql, path=None):
        """One integer from a query on the jobs database: sqlite3 on the file, psql on
        PostgreSQL."""
        if not PG:
            import sqlite3
            con = sqlite3.connect(path or self.db)
            v = con.execute(sql).fetchone()[0]
            con.close()
            return int(v)
        self.db_url(path)
        return int(pg_server().psql(sql + ";\n", self.pg_dbs[path or self.db]).strip())

    def close(self, keep=False):
        for d in self.daemons:
            d.kill9()
        if not keep:
            shutil.rmtree(self.dir, ignore_errors=True)


class Skip(Exception):
    """Raised by a test that cannot run here (its reason the message): main() counts it as
    skipped, not as passed or failed."""


def need(binary, package):
    """The path of a program the test runs (LAMMPS, mpirun, ...); a clear failure when it is
    missing: these tests never skip."""
    path = shutil.which(binary)
    if not path:
        raise AssertionError(
            "`%s` is not on PATH: install the Debian package `%s` (bash deploy/install-deps.sh "
            "--test installs it; CI does). This test never skips." % (binary, package))
    return path


def run_program(cmd, cwd, what):
    """Runs cmd in cwd (one OpenMP thread) and returns its stdout and stderr; a failure, named
    by what, when it exits non-zero, prints a line starting with ERROR or takes longer than
    PROGRAM_TIMEOUT."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    t0 = time.time()
    try:
        p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env,
                           timeout=PROGRAM_TIMEOUT)
    except subprocess.TimeoutExpired as e:
        raise AssertionError("%s did not finish in %ds: %s" % (what, PROGRAM_TIMEOUT, cmd)) from e
    out = p.stdout + p.stderr
    if p.returncode != 0 or re.search(r"^ERROR", out, re.M):
        raise AssertionError("%s failed (exit %d): %s\n%s" % (what, p.returncode, cmd, out[-4000:]))
    print("    %s: %.2fs" % (what, time.time() - t0), flush=True)
    return out


def check_error_body(status, body, code, pointer=None):
    """Every 4xx/5xx body is {"error": {"code", "message", "pointer"?}}."""
    assert isinstance(body, dict) and set(body) == {"error"}, body
    e = body["error"]
    assert e.get("code") == code, (status, e, code)
    assert isinstance(e.get("message"), str) and e["message"], e
    if pointer is not None:
        assert e.get("pointer") == pointer, (e, pointer)


def refused(d, spec, pointer, needle=None, code="invalid_spec"):
    """POST /v1/jobs of spec is refused with 422, the error at pointer (and its message starting
    with it, holding needle)."""
    st, _, j = d.json("POST", "/v1/jobs", spec)
    assert st == 422, (st, j, pointer)
    check_error_body(st, j, code, pointer)
    assert j["error"]["message"].startswith(pointer), j
    if needle:
        assert needle in j["error"]["message"], (j, needle)


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
                                                                       "porosity", "k0"), b
    assert isinstance(h["target"], (int, float)), b
    assert h["achieved"] is None or isinstance(h["achieved"], (int, float)), b


def main(tests):
    """Runs test functions f(binary, env) in order; prints a summary; exit status 1 on failure."""
    if len(sys.argv) < 2:
        print("usage: %s path/to/grainpackd" % sys.argv[0])
        sys.exit(2)
    binary = sys.argv[1]
    failed = 0
    skipped = 0
    t_all = time.time()
    for t in tests:
        if PG and t.__name__ in PG_SKIP:
            skipped += 1
            print("SKIP %-40s on PostgreSQL: %s" % (t.__name__, PG_SKIP[t.__name__]), flush=True)
            continue
        env = Env(binary)
        t0 = time.time()
        try:
            t(env)
            print("PASS %-40s %.2fs" % (t.__name__, time.time() - t0), flush=True)
            env.close()
        except Skip as e:
            skipped += 1
            print("SKIP %-40s %s" % (t.__name__, e), flush=True)
            env.close()
        except Exception:
            failed += 1
            print("FAIL %-40s %.2fs" % (t.__name__, time.time() - t0), flush=True)
            traceback.print_exc()
            for d in env.daemons:
                print("---- daemon log %s ----\n%s" % (d.log_path, d.read_log()))
            env.close()
    print("%d passed, %d failed, %d skipped (%s, %.1fs)" % (
        len(tests) - failed - skipped, failed, skipped, DB_MODE, time.time() - t_all))
    if _pg is not None:
        _pg.stop()
    sys.exit(1 if failed else 0)
