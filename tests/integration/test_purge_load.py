"""Purging a job of hundreds of MB breaks nothing else (api.md "DELETE /v1/jobs/{id}",
operations.md "Retention and purge").

test_purge_under_load: a 3D job with a result of about 400 MB (and its export pack) has
succeeded; a longer job runs; DELETE ?purge=1 of the large one answers 204 at once and the job
is gone; while the daemon frees its space, 50 submits are made from 10 threads and health is
polled every 0.1 s. Every submit answers 201, every submitted job and the running one succeed,
every health answer is 200 "ok" within its latency limit, and (SQLite) the write-ahead log stays
small while the file shrinks back.

test_retention_under_load: the same with the retention sweep purging the large job at start-up
(its finished_at backdated), submits made from the moment the daemon listens.
"""
import os
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

# spheres of 1-2 mm in a 9 mm box, tiled 16 x 16 x 16 with their contacts: a result of about
# 410 MB in about 11 s of one core
LARGE_3D = dict(gpd.SMALL_3D, box=[0.009, 0.009, 0.009], tiling=[16, 16, 16],
                outputs=["spheres", "contacts"])
# a job running across the purge: a few seconds, its result stored while the space is freed
RUNNING_2D = dict(gpd.SMALL_2D, seed=11, particles=1500, contour_points=256,
                  imc={"max_steps": 0})
TINY = dict(gpd.SMALL_2D, particles=20, contour_points=16, outputs=["grains"])
SUBMITS, SUBMIT_THREADS = 50, 10
HEALTH_LIMIT_S = 1.0 * gpd.TIME_SCALE   # every health answer
SUBMIT_LIMIT_S = 2.0 * gpd.TIME_SCALE   # every submit
PURGE_LIMIT_S = 0.5 * gpd.TIME_SCALE    # the DELETE ?purge=1 itself
WAL_LIMIT = 160e6                       # bytes, the largest -wal seen (journal_size_limit 64 MB)


def file_size(path):
    try:
        return os.path.getsize(path)
    except OSError:
        return 0


class Load:
    """Submits and health polls on threads while the space of a purge is freed."""

    def __init__(self, env, d):
        self.env, self.d = env, d
        self.errors, self.ids = [], []
        self.submit_s, self.health_s = [], []
        self.wal_peak = 0
        self.stop = threading.Event()
        self.mu = threading.Lock()

    def submitter(self, k):
        for i in range(SUBMITS // SUBMIT_THREADS):
            t0 = time.time()
            st, _, j = self.d.json("POST", "/v1/jobs", dict(TINY, seed=1000 * k + i))
            dt = time.time() - t0
            with self.mu:
                self.submit_s.append(dt)
                if st != 201:
                    self.errors.append("submit: %s %r" % (st, j))
                else:
                    self.ids.append(j["id"])

    def health(self):
        while not self.stop.is_set():
            t0 = time.time()
            st, _, j = self.d.json("GET", "/v1/health")
            dt = time.time() - t0
            with self.mu:
                self.health_s.append(dt)
                if st != 200 or j["status"] != "ok" or j["database"] != "ok":
                    self.errors.append("health: %s %r" % (st, j))
            if not gpd.PG:
                self.wal_peak = max(self.wal_peak, file_size(self.env.db + "-wal"))
            time.sleep(0.1)

    def run(self, until_done, timeout):
        """Submits and polls until until_done() is true (and the submits are made)."""
        h = threading.Thread(target=self.health)
        h.start()
        subs = [threading.Thread(target=self.submitter, args=(k,))
                for k in range(SUBMIT_THREADS)]
        for t in subs:
            t.start()
        t0 = time.time()
        done_s = None
        while time.time() - t0 < timeout:
            if until_done():
                done_s = time.time() - t0
                break
            time.sleep(0.1)
        for t in subs:
            t.join(120)
        self.stop.set()
        h.join(30)
        return done_s

    def wal_note(self):
        return "" if gpd.PG else "; largest WAL seen %.1f MB" % (self.wal_peak / 1e6)

    def check(self, what):
        d = self.d
        assert not self.errors, self.errors[:5]
        assert len(self.ids) == SUBMITS, len(self.ids)
        for jid in self.ids:
            j = d.wait(jid, timeout=300)
            assert j["status"] == "succeeded", j
        print("  %s: %d submits (slowest %.3f s), %d health answers (slowest %.3f s), all ok"
              % (what, len(self.submit_s), max(self.submit_s), len(self.health_s),
                 max(self.health_s)))
        assert max(self.submit_s) <= SUBMIT_LIMIT_S, sorted(self.submit_s)[-5:]
        assert max(self.health_s) <= HEALTH_LIMIT_S, sorted(self.health_s)[-5:]


def make_large(d):
    t0 = time.time()
    jid = d.submit(LARGE_3D)
    j = d.wait(jid, timeout=600, interval=0.5)
    assert j["status"] == "succeeded", j
    st, h, _ = d.request("HEAD", "/v1/jobs/%s/result" % jid)
    size = int(h["Content-Length"])
    print("  the large job: a result of %.0f MB, made and stored in %.1f s"
          % (size / 1e6, time.time() - t0))
    assert size > 300e6, size
    return jid, size


def wal_checkpointed(env, timeout=120):
    """Waits until the large job's commit has left the WAL (the daemon checkpoints once its
    workers are idle), so that what the WAL holds next is the purge's."""
    if gpd.PG:
        return
    deadline = time.time() + timeout
    while file_size(env.db + "-wal") > 64e6:
        assert time.time() < deadline, file_size(env.db + "-wal")
        time.sleep(0.2)


def db_bytes(env):
    if gpd.PG:
        return env.query_int("SELECT pg_database_size(current_database())")
    return file_size(env.db) + file_size(env.db + "-wal")


def space_freed(env, big, target):
    """A check that the large job's rows are gone (PostgreSQL: its row, kept as 'purged' until
    its values are deleted; SQLite: its file space given back)."""
    def done():
        if gpd.PG:
            return env.query_int("SELECT count(*) FROM value_parts") == 0 and env.query_int(
                "SELECT count(*) FROM jobs WHERE id = '%s'" % big) == 0
        return file_size(env.db) + file_size(env.db + "-wal") <= target
    return done


def test_purge_under_load(env):
    d = env.daemon(workers=2)
    base = db_bytes(env)
    big, size = make_large(d)
    wal_checkpointed(env)
    run_id = d.submit(RUNNING_2D)
    d.wait(run_id, states=("running",), timeout=60, interval=0.02)
    t0 = time.time()
    st, _, b = d.request("DELETE", "/v1/jobs/%s?purge=1" % big)
    purge_s = time.time() - t0
    assert st == 204 and b == b"", (st, b)
    print("  DELETE ?purge=1 of %.0f MB answered 204 in %.3f s" % (size / 1e6, purge_s))
    for path in ("", "/result", "/export?format=csv"):
        assert d.json("GET", "/v1/jobs/%s%s" % (big, path))[0] == 404, path
    assert big not in [x["id"] for x in d.json("GET", "/v1/jobs?limit=500")[2]["jobs"]]
    load = Load(env, d)
    freed_s = load.run(space_freed(env, big, base + 0.2 * size), timeout=240)
    assert freed_s is not None, "the space of the purged job was not given back: %d bytes" % (
        db_bytes(env))
    print("  its space was freed %.1f s after the purge%s" % (freed_s, load.wal_note()))
    j = d.wait(run_id, timeout=300)
    assert j["status"] == "succeeded", j
    load.check("purge")
    assert purge_s <= PURGE_LIMIT_S, purge_s
    assert load.wal_peak <= WAL_LIMIT, load.wal_peak
    assert d.json("DELETE", "/v1/jobs/%s?purge=1" % big)[0] == 404
    assert d.stop() == 0, d.read_log()


def test_retention_under_load(env):
    d = env.daemon(workers=2)
    base = db_bytes(env)
    big, size = make_large(d)
    assert d.stop() == 0, d.read_log()
    env.execute("UPDATE jobs SET finished_at=? WHERE id=?", ("2000-01-01T00:00:00.000Z", big))
    d = env.daemon(workers=2, extra=("--retain-days", "1"))
    run_id = d.submit(RUNNING_2D)
    load = Load(env, d)
    freed_s = load.run(space_freed(env, big, base + 0.2 * size), timeout=240)
    assert freed_s is not None, "the space of the expired job was not given back"
    print("  retention: the expired job's space was freed %.1f s after the start%s"
          % (freed_s, load.wal_note()))
    assert d.json("GET", "/v1/jobs/" + big)[0] == 404
    assert d.wait(run_id, timeout=300)["status"] == "succeeded"
    load.check("retention")
    assert load.wal_peak <= WAL_LIMIT, load.wal_peak
    assert d.stop() == 0, d.read_log()


if __name__ == "__main__":
    gpd.main([test_purge_under_load, test_retention_under_load])
