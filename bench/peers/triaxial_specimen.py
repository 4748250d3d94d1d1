#!/usr/bin/env python3
"""triaxial_specimen.py -- builds a Dang & Meguid (2010) specimen with the real grainpackd and
writes what bench/peers/yade_triaxial.py needs to run the same triaxial test in YADE.

    python3 bench/peers/triaxial_specimen.py OUT_DIR [--grainpackd PATH | --url URL]
        [--small] [--box 0.5] [--porosity 0.38] [--sieve '[[10,0],[20,2],...]'] [--seed 7]
        [--job-threads 1] [--timeout 3600]

Without --url it starts its own daemon (127.0.0.1 port 0, a temporary SQLite database, one
worker) and stops it at the end; --grainpackd defaults to $GRAINPACKD, else build/server/grainpackd
of this checkout. It submits a `spheres-3d` spec -- by default the paper's S0: a 0.5 m cube, the
Table 2 sieve by weight, porosity 0.38, the Table 1 material, NO tiling (the export is then the
sample S0 as the job ended) -- waits for it to succeed, and writes to OUT_DIR:

    spheres.txt  GET /v1/jobs/{id}/export?format=yade  ("x y z r" per line, SI; ymport.text)
    box.json     {"lo": [0,0,0], "hi": box, "box": box, "job": id, "axial_axis": 2, and
                  grainpack's own figures: particles, porosity, coordination numbers, stress
                  (Pa, tension negative as grainpack reports it), stability, steps, dt}
    spec.json    the spec submitted;  job.json  the final job object;  result.json  the result

--small is a CI-sized variant (a few hundred spheres): a 0.3 m cube of the same sieve at
porosity 0.42. A small box cannot reach 0.38 with this sieve (d_max 100 mm: the walls loosen the
packing; grainpack then fails with `infeasible`, e.g. 0.25 m stalls at 0.428 and 0.3 m near 0.40),
so the small variant is looser than S0. Any of --box/--porosity/--sieve overrides the preset.

Then:  yade -j1 -n -x bench/peers/yade_triaxial.py OUT_DIR/spheres.txt OUT_DIR/box.json OUT.json
Python standard library only. Exit status 1 (with the daemon's message) when the job fails.
"""
import argparse
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))

TABLE2_SIEVE = [[10, 0], [20, 2], [50, 50], [80, 95], [100, 100]]  # mm, % passing by weight
TABLE1 = {"density": 2600, "young": 15e6, "poisson": 0.5, "friction_deg": 18, "damping": 0.2}
S0 = {"box": 0.5, "porosity": 0.38}
SMALL = {"box": 0.3, "porosity": 0.42}


def make_spec(small=False, seed=7, box=None, porosity=None, sieve=None):
    """The spheres-3d spec submitted: S0 (or the --small preset), each of box (cube edge, m),
    porosity and sieve (rows [d_mm, % passing by weight]) overriding the preset when given.
    tests/integration/test_triaxial_yade.py imports it."""
    preset = SMALL if small else S0
    edge = box if box is not None else preset["box"]
    return {"kind": "spheres-3d", "seed": seed, "box": [edge, edge, edge],
            "sieve": sieve if sieve else TABLE2_SIEVE, "sieve_units": "mm",
            "porosity": porosity if porosity is not None else preset["porosity"],
            "material": dict(TABLE1),
            "outputs": ["spheres", "contacts", "fabric", "stress"]}  # no tiling: the sample S0


def box_info(jid, spec, result):
    """box.json for yade_triaxial.py: the walls at [0, box] and grainpack's own figures."""
    box = result["box"]
    st = result.get("stats", {})
    return {"lo": [0.0, 0.0, 0.0], "hi": box, "box": box, "axial_axis": 2,
            "job": jid, "spec": spec,
            "grainpack": {k: st.get(k) for k in (
                "particles", "porosity", "coordination_number", "coordination_spheres",
                "fabric", "stress", "stability", "stop_reason", "steps", "dt",
                "compaction_friction_deg", "contacts", "wall_contacts")},
            "timings": result.get("timings")}


def log(msg):
    sys.stderr.write("triaxial_specimen: %s\n" % msg)
    sys.stderr.flush()


class Daemon:
    """grainpackd on 127.0.0.1:0 with a temporary database (as tests/integration/gpd.py)."""

    def __init__(self, binary, job_threads):
        self.dir = tempfile.mkdtemp(prefix="gp-triax-")
        self.log_path = os.path.join(self.dir, "grainpackd.log")
        self.log = open(self.log_path, "wb")
        cmd = [binary, "--listen", "127.0.0.1:0", "--db", os.path.join(self.dir, "jobs.db"),
               "--workers", "1", "--job-threads", str(job_threads),
               "--job-timeout", "0"]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=self.log)
        line = b""
        deadline = time.time() + 30
        while not line.endswith(b"\n"):
            left = deadline - time.time()
            if left <= 0 or self.proc.poll() is not None:
                self.stop()
                raise SystemExit("grainpackd did not print its address:\n" + self.tail())
            r, _, _ = select.select([self.proc.stdout], [], [], left)
            if r:
                ch = os.read(self.proc.stdout.fileno(), 1)
                if ch:
                    line += ch
        text = line.decode().strip()
        if not text.startswith("listening on http://"):
            self.stop()
            raise SystemExit("unexpected first line from grainpackd: " + text)
        self.url = text[len("listening on "):]

    def tail(self):
        try:
            with open(self.log_path, "rb") as f:
                return f.read().decode(errors="replace")[-3000:]
        except OSError:
            return ""

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        self.proc.stdout.close()
        self.log.close()
        shutil.rmtree(self.dir, ignore_errors=True)


def request(url, method="GET", body=None, timeout=60):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method=method,
                                 headers={"Content-Type": "application/json"} if data else {})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


def get_json(url):
    st, b = request(url)
    if st != 200:
        raise SystemExit("GET %s: %d %s" % (url, st, b[:500].decode(errors="replace")))
    return json.loads(b)


def build(base, spec, out, timeout):
    st, b = request(base + "/v1/jobs", "POST", spec)
    if st != 201:
        raise SystemExit("submit refused: %d %s" % (st, b.decode(errors="replace")))
    jid = json.loads(b)["id"]
    log("job %s submitted (%s)" % (jid, base))
    t0 = time.time()
    last = None
    while True:
        job = get_json(base + "/v1/jobs/" + jid)
        if job["status"] in ("succeeded", "failed", "cancelled"):
            break
        p = job.get("progress") or {}
        now = "%s %.0f%%" % (p.get("phase"), 100 * (p.get("fraction") or 0))
        if now != last:
            log("  %6.1f s  %s %s" % (time.time() - t0, now, json.dumps(p.get("detail") or {})))
            last = now
        if time.time() - t0 > timeout:
            request(base + "/v1/jobs/" + jid, "DELETE")
            raise SystemExit("job %s not finished after %d s (cancelled)" % (jid, timeout))
        time.sleep(0.5)
    with open(os.path.join(out, "job.json"), "w") as f:
        json.dump(job, f, indent=1)
    if job["status"] != "succeeded":
        raise SystemExit("job %s %s: %s" % (jid, job["status"], json.dumps(job.get("error"))))
    result = get_json(base + "/v1/jobs/%s/result" % jid)
    st, text = request(base + "/v1/jobs/%s/export?format=yade" % jid, timeout=600)
    if st != 200:
        raise SystemExit("export: %d %s" % (st, text[:500].decode(errors="replace")))
    return jid, job, result, text


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="output folder (created)")
    ap.add_argument("--grainpackd", default=os.environ.get("GRAINPACKD") or
                    os.path.join(REPO, "build", "server", "grainpackd"))
    ap.add_argument("--url", help="use this running daemon (http://host:port) instead")
    ap.add_argument("--small", action="store_true",
                    help="CI-sized: 0.3 m cube at porosity 0.42 (a few hundred spheres)")
    ap.add_argument("--box", type=float, help="cube edge in m (S0: 0.5)")
    ap.add_argument("--porosity", type=float, help="target porosity (S0: 0.38)")
    ap.add_argument("--sieve", help="JSON rows [[d_mm, %% passing by weight], ...] (Table 2)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--job-threads", type=int, default=1,
                    help="threads of the job's DEM (the result does not depend on it)")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds to wait for the job")
    a = ap.parse_args()

    spec = make_spec(small=a.small, seed=a.seed, box=a.box, porosity=a.porosity,
                     sieve=json.loads(a.sieve) if a.sieve else None)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "spec.json"), "w") as f:
        json.dump(spec, f, indent=1)

    daemon = None
    if a.url:
        base = a.url.rstrip("/")
    else:
        if not os.path.exists(a.grainpackd):
            raise SystemExit("no grainpackd at %s (build it, or pass --grainpackd / --url)"
                             % a.grainpackd)
        daemon = Daemon(a.grainpackd, a.job_threads)
        base = daemon.url
    try:
        jid, job, result, text = build(base, spec, a.out, a.timeout)
    finally:
        if daemon:
            daemon.stop()

    with open(os.path.join(a.out, "spheres.txt"), "wb") as f:
        f.write(text)
    with open(os.path.join(a.out, "result.json"), "w") as f:
        json.dump(result, f)
    box = result["box"]
    st = result.get("stats", {})
    with open(os.path.join(a.out, "box.json"), "w") as f:
        json.dump(box_info(jid, spec, result), f, indent=1)
    n = sum(1 for l in text.decode().splitlines() if l and not l.startswith("#"))
    por = (st.get("porosity") or {}).get("achieved")
    log("job %s: %d spheres, box %s, porosity %s -> %s" % (jid, n, box, por, a.out))
    print("yade -j1 -n -x %s %s %s %s" % (os.path.join(HERE, "yade_triaxial.py"),
                                          os.path.join(a.out, "spheres.txt"),
                                          os.path.join(a.out, "box.json"),
                                          os.path.join(a.out, "out.json")))


if __name__ == "__main__":
    main()
