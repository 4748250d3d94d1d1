"""Results and exports larger than the in-memory threshold (256 KiB) are streamed from SQLite:
a tiled 3D job of ~12,000 spheres; its result (Content-Length, parsed whole) and its csv export
(chunked) must agree float for float, survive a client that hangs up mid-download, and a
restarted daemon must still serve them."""
import http.client
import json
import os
import sys
import urllib.parse

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

TILED_3D = dict(gpd.SMALL_3D, tiling=[6, 6, 6], outputs=["spheres"])


def get_result_and_csv(d, jid):
    st, h, body = d.request("GET", "/v1/jobs/%s/result" % jid, timeout=120)
    assert st == 200, (st, body[:200])
    assert int(h["Content-Length"]) == len(body) > 256 * 1024, (h.get("Content-Length"), len(body))
    res = json.loads(body)
    st, h, csv = d.request("GET", "/v1/jobs/%s/export?format=csv" % jid, timeout=120)
    assert st == 200, (st, csv[:200])
    assert h.get("Transfer-Encoding") == "chunked", dict(h)
    return res, csv


def check_same(res, csv):
    lines = csv.decode().splitlines()
    assert lines[0] == "x,y,z,r", lines[0]
    rows = [tuple(float(v) for v in ln.split(",")) for ln in lines[1:]]
    spheres = [tuple(s) for s in res["spheres"]]
    assert len(rows) == len(spheres) == res["stats"]["particles"], (len(rows), len(spheres))
    assert rows == spheres  # bit for bit: both are written with 17 significant digits


def hang_up_mid_download(d, jid):
    """A client that reads 100 KB of a streamed export and closes the socket."""
    u = urllib.parse.urlparse(d.url)
    for path in ("/v1/jobs/%s/export?format=vtk" % jid, "/v1/jobs/%s/result" % jid):
        c = http.client.HTTPConnection(u.hostname, u.port, timeout=30)
        c.request("GET", path)
        r = c.getresponse()
        assert r.status == 200, r.status
        assert len(r.read(100 * 1024)) == 100 * 1024
        c.close()


def test_large_result_streams(env):
    d = env.daemon(workers=1)
    jid = d.submit(TILED_3D)
    job = d.wait(jid, timeout=300)
    assert job["status"] == "succeeded", job
    res, csv = get_result_and_csv(d, jid)
    assert res["tiling"] == [6, 6, 6] and res["stats"]["particles"] > 6 ** 3 * 20, res["stats"]
    check_same(res, csv)
    hang_up_mid_download(d, jid)
    # the daemon is still healthy and serves the same bytes again, also after a restart
    st, _, j = d.json("GET", "/v1/health")
    assert st == 200, (st, j)
    res2, csv2 = get_result_and_csv(d, jid)
    assert csv2 == csv and res2 == res
    assert d.stop() == 0, d.read_log()
    d2 = env.daemon(workers=1)
    res3, csv3 = get_result_and_csv(d2, jid)
    assert csv3 == csv and res3 == res
    assert d2.stop() == 0, d2.read_log()


if __name__ == "__main__":
    gpd.main([test_large_result_streams])
