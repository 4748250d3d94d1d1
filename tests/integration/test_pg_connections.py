"""Slow downloads on one daemon leave the PostgreSQL server's connections to the others
(api.md "Errors": 503 busy; operations.md "Many daemons on one PostgreSQL server").

test_slow_readers_leave_second_daemon: two daemons on one server whose max_connections is 100
(Debian's default). 200 clients start downloading a 30 MB result from daemon A and then read
nothing more, each holding its download open. A holds at most --db-connections (32) database
connections: the downloads it cannot serve get 503 busy with Retry-After at once; the server
never holds more than A's share and B's. Meanwhile daemon B serves 20 submits (every one 201,
every job succeeded) and downloads of the same result, whole and equal. Once the slow clients
hang up, A serves the download again.

test_stalled_download_ends_its_transaction: a download whose client stops reading holds a
transaction (its snapshot) only as long as idle_in_transaction_session_timeout (60 s; 2 s here
through a testing hook): then the server ends it, and the daemon's idle transactions are gone.

Always on PostgreSQL (whatever GP_TEST_DB says): the test starts its own server (gpd.PgServer).
"""
import json
import os
import socket
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

gpd.PG, gpd.DB_MODE = True, "postgresql"  # this test is PostgreSQL's own
SERVER_MAX_CONNECTIONS = 100
SLOW_READERS = 200
DB_CONNECTIONS = 32  # the daemons' default (--db-connections)
# a result of about 30 MB: more than the socket buffers between a daemon and a client that
# stopped reading take, so that each such download stays open
BIG_2D = {"kind": "fourier-voronoi-2d", "seed": 5, "particles": 4000, "contour_points": 128,
          "imc": {"max_steps": 0}, "outputs": ["grains", "odec", "descriptors", "cells"]}
TINY = dict(gpd.SMALL_2D, particles=20, contour_points=16, outputs=["grains"])


def slow_reader(d, path):
    """A client that asks for path, reads the answer's head and a little of its body, and then
    reads nothing more (its receive window small). Returns (socket, status, headers)."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.settimeout(30)
    s.connect(("127.0.0.1", d.port()))
    s.sendall(("GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n" % path).encode())
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = s.recv(4096)
        if not chunk:
            break
        data += chunk
    head = data.split(b"\r\n\r\n", 1)[0].decode("latin-1").split("\r\n")
    headers = {k.lower(): v for k, v in (ln.split(": ", 1) for ln in head[1:] if ": " in ln)}
    return s, int(head[0].split(" ")[1]), headers


def server_connections(env):
    """Client connections the server holds for the test's database (None when even psql is
    refused: the server is full)."""
    try:
        return int(gpd.pg_server().psql(
            "SELECT count(*) FROM pg_stat_activity WHERE datname = current_database() "
            "AND pid <> pg_backend_pid();", env.pg_dbs[env.db]).strip())
    except RuntimeError as e:
        print("  psql: %s" % str(e).strip().splitlines()[-1])
        return None


def test_slow_readers_leave_second_daemon(env):
    a = env.daemon(workers=1, extra=["--timeout", "300"])
    b = env.daemon(workers=1)
    jid = a.submit(BIG_2D)
    assert a.wait(jid, timeout=300)["status"] == "succeeded"
    path = "/v1/jobs/%s/result" % jid
    st, _, whole = b.request("GET", path, timeout=120)
    assert st == 200 and len(whole) > 20e6, (st, len(whole))

    readers, statuses, busy = [], {}, None
    t0 = time.time()
    try:
        for _ in range(SLOW_READERS):
            s, st, h = slow_reader(a, path)
            readers.append(s)
            statuses[st] = statuses.get(st, 0) + 1
            if st == 503:
                busy = h
        opened_s = time.time() - t0
        held = server_connections(env)
        print("  %d slow readers on A in %.1f s: %s; the server holds %s connections of %d"
              % (SLOW_READERS, opened_s, statuses, held, SERVER_MAX_CONNECTIONS))
        # B meanwhile: submits and downloads
        t1 = time.time()
        ids = []
        for i in range(20):
            st, _, j = b.json("POST", "/v1/jobs", dict(TINY, seed=500 + i))
            assert st == 201, (st, j)
            ids.append(j["id"])
        for i in range(3):
            st, _, body = b.request("GET", path, timeout=120)
            assert st == 200 and body == whole, (st, body[:200])
        for k in ids:
            assert b.wait(k, timeout=120)["status"] == "succeeded"
        print("  B meanwhile: 20 submits (201, every job succeeded) and 3 downloads of %.0f MB "
              "in %.1f s" % (len(whole) / 1e6, time.time() - t1))
        assert statuses.get(200, 0) >= 1 and set(statuses) <= {200, 503}, statuses
        assert busy is not None, statuses
        assert int(busy.get("retry-after", "0")) >= 1, busy
        assert held is not None and held <= 2 * DB_CONNECTIONS, held
        # the body of a 503: the JSON error object
        st, h, e = a.json("GET", path)
        assert st == 503, (st, e)
        gpd.check_error_body(st, e, "busy")
        assert int(h["Retry-After"]) >= 1, dict(h)
        # a picture whose items are read from the stored result (streamed): busy too, not 500
        st, h, e = a.json("GET", "/v1/jobs/%s/svg?view=cells" % jid)
        assert st == 503 and int(h["Retry-After"]) >= 1, (st, e)
        gpd.check_error_body(st, e, "busy")
        assert a.json("GET", "/v1/health")[0] == 200
    finally:
        for s in readers:
            s.close()
    # the slow clients gone, A serves the download again
    deadline = time.time() + 30
    while True:
        st, _, body = a.request("GET", path, timeout=120)
        if st == 200 or time.time() > deadline:
            break
        time.sleep(0.5)
    assert st == 200 and body == whole, st
    print("  A after the slow readers hung up: the download whole again")
    assert a.stop() == 0, a.read_log()
    assert b.stop() == 0, b.read_log()


def in_transaction(env):
    """The daemons' sessions in a transaction (a download's snapshot, or a moment's write)."""
    return int(gpd.pg_server().psql(
        "SELECT count(*) FROM pg_stat_activity WHERE datname = current_database() "
        "AND pid <> pg_backend_pid() AND xact_start IS NOT NULL;", env.pg_dbs[env.db]).strip())


def test_stalled_download_ends_its_transaction(env):
    d = env.daemon(workers=1, extra=["--timeout", "300"], env={"GRAINPACK_TEST_PG_IDLE_S": "2"})
    jid = d.submit(BIG_2D)
    assert d.wait(jid, timeout=300)["status"] == "succeeded"
    readers = []
    try:
        for _ in range(5):
            s, st, _ = slow_reader(d, "/v1/jobs/%s/result" % jid)
            assert st == 200, st
            readers.append(s)
        time.sleep(0.5)  # the downloads have filled the sockets' buffers and wait
        held = in_transaction(env)
        assert held >= 5, held
        t0 = time.time()
        while in_transaction(env) and time.time() - t0 < 30:
            time.sleep(0.25)
        left = in_transaction(env)
        print("  5 stalled downloads held %d transactions; none left %.1f s later"
              % (held, time.time() - t0))
        assert left == 0, left
        st, _, e = d.json("GET", "/v1/health")
        assert st == 200 and e["status"] == "ok", (st, e)
    finally:
        for s in readers:
            s.close()
    st, _, body = d.request("GET", "/v1/jobs/%s/result" % jid, timeout=120)
    assert st == 200 and json.loads(body)["stats"], st
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd._pg = gpd.PgServer(max_connections=SERVER_MAX_CONNECTIONS).start()
    gpd.main([test_slow_readers_leave_second_daemon, test_stalled_download_ends_its_transaction])
