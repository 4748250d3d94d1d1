"""The request bodies a daemon holds at once are bounded (4 times --max-body, all connections
together): with --max-body 1 MiB, three clients holding 0.9 MB bodies half sent leave room for
small requests, but a fourth body at the limit is dropped and answered 503 busy with Retry-After (not
413: it is within its own limit); once the three are gone the same body is read and parsed."""
import json
import os
import socket
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

LIMIT = 1 << 20
BODY = 900_000


def head(length):
    return ("POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
            "Content-Length: %d\r\n\r\n" % length).encode()


def test_bodies_held(env):
    d = env.daemon(workers=1, extra=("--max-body", str(LIMIT)))
    held = []
    try:
        for _ in range(3):
            s = socket.create_connection(("127.0.0.1", d.port()), timeout=10)
            s.sendall(head(BODY + 100_000) + b" " * BODY)  # 100 kB never sent
            held.append(s)
        time.sleep(0.5 * gpd.TIME_SCALE)
        # a small request still fits
        st, _, j = d.json("POST", "/v1/jobs", {"kind": "fourier-voronoi-2d", "particles": "x"})
        assert st == 422, (st, j)
        # a fourth at the limit does not (3 x 1 MiB held, its 1 MiB + 1 over 4 MiB): 503 busy,
        # its body read and dropped
        st, h, body = d.raw(head(LIMIT), [b" " * LIMIT])
        assert st == 503, (st, body[:300])
        assert h.get("retry-after") == "5", h
        gpd.check_error_body(st, json.loads(body), "busy")
        assert b"--max-body" in body, body
    finally:
        for s in held:
            s.close()
    time.sleep(0.5 * gpd.TIME_SCALE)
    # the held bodies released: the same body is read and parsed (spaces: no JSON value)
    st, _, body = d.raw(head(LIMIT), [b" " * LIMIT])
    assert st == 400 and b"invalid_json" in body, (st, body[:300])
    st, _, j = d.json("GET", "/v1/health")
    assert st == 200 and j["status"] == "ok", j
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_bodies_held])
