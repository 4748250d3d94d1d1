"""200 concurrent status pollers (threads) while jobs run: no errors, every answer a valid job
object."""
import json
import os
import sys
import threading
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

POLLERS = 200
DURATION_S = 4.0


def test_200_pollers(env):
    d = env.daemon(workers=2)
    ids = [d.submit(dict(gpd.SMALL_2D, seed=i, particles=100)) for i in range(6)]
    errors, counts = [], [0] * POLLERS
    start = threading.Barrier(POLLERS)

    def poll(k):
        jid = ids[k % len(ids)]
        url = d.url + "/v1/jobs/" + jid
        try:
            start.wait(30)
        except threading.BrokenBarrierError:
            errors.append("barrier")
            return
        t_end = time.time() + DURATION_S
        while time.time() < t_end:
            try:
                with urllib.request.urlopen(url, timeout=20) as r:
                    j = json.loads(r.read())
                    if r.status != 200 or j["id"] != jid:
                        errors.append("bad answer %s %r" % (r.status, j))
                    gpd.check_job_object(j)
                counts[k] += 1
            except Exception as e:  # noqa: BLE001 -- every failure counts
                errors.append(repr(e))
                if len(errors) > 50:
                    return

    threads = [threading.Thread(target=poll, args=(k,)) for k in range(POLLERS)]
    t0 = time.time()
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    elapsed = time.time() - t0
    total = sum(counts)
    print("    %d pollers: %d requests in %.1fs (%.0f req/s), %d errors" %
          (POLLERS, total, elapsed, total / elapsed, len(errors)))
    assert not errors, errors[:5]
    assert all(c > 0 for c in counts), "a poller got no answer"
    for jid in ids:
        assert d.wait(jid)["status"] == "succeeded"
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_200_pollers])
