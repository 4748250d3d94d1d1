#!/usr/bin/env python3
"""compare_builds.py -- do two builds of grainpackd make the same specimens, byte for byte?

    python3 bench/compare_builds.py OLD/grainpackd NEW/grainpackd      compare two binaries
    python3 bench/compare_builds.py BIN --save DIR                     keep one build's files
    python3 bench/compare_builds.py BIN --against DIR                  compare with kept files

For a refactoring that must not change results: each binary runs on its own temporary database
the same specs (both kinds, every output, each size law, a polygon with holes and a circle, a
tiled 3D packing, AD and E3 errors, two worker counts), and for every job the script fetches the
result, the effective spec, every export format of its kind and every SVG view, and compares
them byte for byte. The result's "timings" (seconds measured by the run) is the one member left
out. It prints one table: job, file, bytes, and "same" or the first differing offset; the exit
status is 1 when anything differs. Python standard library only; Linux.
"""
import argparse
import json
import os
import sys
import tempfile
import urllib.error
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_export import start, stop, submit, wait  # noqa: E402

OUT2 = ["grains", "odec", "descriptors", "cells"]
SPECS = {
    "2d-lognormal": {"kind": "fourier-voronoi-2d", "seed": 11, "particles": 300,
                     "size": {"cov": 0.8}, "outputs": OUT2},
    "2d-E3-halton": {"kind": "fourier-voronoi-2d", "seed": 12, "particles": 200,
                     "imc": {"error": "E3", "threshold": 0.01, "init": "halton"},
                     "orientation": {"mean_deg": 30, "anisotropy": 0.5}, "outputs": OUT2},
    "2d-sieve-holes": {"kind": "fourier-voronoi-2d", "seed": 13,
                       "container": {"polygon": [[0, 0], [0.1, 0], [0.1, 0.08], [0, 0.08]],
                                     "holes": [[[0.03, 0.03], [0.05, 0.03], [0.04, 0.05]]]},
                       "size": {"law": "sieve", "sieve": [[3, 0], [5, 60], [8, 100]],
                                "sieve_units": "mm", "of": "grains"},
                       "outputs": OUT2},
    "2d-circle-normal": {"kind": "fourier-voronoi-2d", "seed": 14, "particles": 150,
                         "container": {"circle": {"center": [1e3, -2e3], "radius": 0.5}},
                         "size": {"law": "normal", "cov": 0.3},
                         "shape": {"spectrum": [1, 0, 0.12, 0.06, 0.03, 0.02, 0.01, 0.01, 0.02]},
                         "contour_points": 64, "outputs": OUT2},
    "3d-small": {"kind": "spheres-3d", "seed": 7, "box": [0.006, 0.006, 0.006],
                 "sieve": [[1, 0], [2, 100]], "sieve_units": "mm", "porosity": 0.5,
                 "outputs": ["spheres", "contacts", "fabric", "stress"]},
    "3d-tiled": {"kind": "spheres-3d", "seed": 8, "box": [0.008, 0.008, 0.008],
                 "sieve": [[1, 0], [1.5, 40], [2, 100]], "sieve_units": "mm", "porosity": 0.5,
                 "tiling": [2, 3, 2], "outputs": ["spheres", "contacts", "fabric", "stress"]},
    "3d-stats-only": {"kind": "spheres-3d", "seed": 9, "box": [0.008, 0.008, 0.008],
                      "sieve": [[1, 0], [2, 100]], "sieve_units": "mm", "porosity": 0.5,
                      "tiling": [2, 2, 2], "outputs": ["fabric"]},
}
FORMATS = {"fourier-voronoi-2d": ["lammps", "yade", "vtk", "csv"],
           "spheres-3d": ["lammps", "liggghts", "yade", "vtk", "csv"]}
VIEWS = {"fourier-voronoi-2d": ["packing", "cells", "size", "orientation", "descriptors"],
         "spheres-3d": ["section", "psd"]}


def get(url):
    try:
        with urllib.request.urlopen(url, timeout=300) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


def files_of(binary, workers):
    """{(job, file): bytes} for every spec, run on a fresh daemon with this many workers."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        proc, base = start(binary, os.path.join(tmp, "db.sqlite"), workers)
        try:
            ids = {name: submit(base, spec) for name, spec in SPECS.items()}
            for name, jid in ids.items():
                j = wait(base, jid, name)
                kind = SPECS[name]["kind"]
                out[(name, "status")] = json.dumps([j["status"], j["error"]]).encode()
                st, b = get(base + "/v1/jobs/%s/result" % jid)
                if st == 200:
                    r = json.loads(b)
                    r.pop("timings", None)
                    b = json.dumps(r, sort_keys=True).encode()
                out[(name, "result")] = b
                out[(name, "spec")] = get(base + "/v1/jobs/%s/spec" % jid)[1]
                for f in FORMATS[kind]:
                    out[(name, "export " + f)] = get(base + "/v1/jobs/%s/export?format=%s" %
                                                     (jid, f))[1]
                for v in VIEWS[kind]:
                    out[(name, "svg " + v)] = get(base + "/v1/jobs/%s/svg?view=%s" % (jid, v))[1]
                for k in out:  # error bodies name the job
                    if k[0] == name:
                        out[k] = out[k].replace(jid.encode(), b"<id>")
        finally:
            stop(proc)
    return out


def first_diff(a, b):
    for i, (x, y) in enumerate(zip(a, b)):
        if x != y:
            return i
    return min(len(a), len(b))


def load_dir(d):
    with open(os.path.join(d, "index.json")) as f:
        index = json.load(f)
    out = {}
    for k, fn in index:
        with open(os.path.join(d, fn), "rb") as f:
            out[tuple(k)] = f.read()
    return out


def save_dir(d, files):
    os.makedirs(d, exist_ok=True)
    index = []
    for i, (k, v) in enumerate(sorted(files.items())):
        fn = "%03d.bin" % i
        with open(os.path.join(d, fn), "wb") as f:
            f.write(v)
        index.append([list(k), fn])
    with open(os.path.join(d, "index.json"), "w") as f:
        json.dump(index, f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("old")
    ap.add_argument("new", nargs="?")
    ap.add_argument("--save")
    ap.add_argument("--against")
    args = ap.parse_args()
    runs = {}
    for w in (1, 2):
        runs[w] = files_of(args.old, w)
    # the build agrees with itself across worker counts (determinism), then with the other
    a = runs[1]
    differ = [k for k in a if a[k] != runs[2][k]]
    bad = len(differ)
    print("worker counts 1 and 2: %d of %d files differ %s" % (bad, len(a), differ or ""))
    if args.save:
        save_dir(args.save, a)
        print("saved %d files to %s" % (len(a), args.save))
        return 1 if bad else 0
    b = load_dir(args.against) if args.against else files_of(args.new, 2)
    print("%-18s %-20s %12s  %s" % ("job", "file", "bytes", "verdict"))
    for k in sorted(set(a) | set(b)):
        x, y = a.get(k), b.get(k)
        if x is None or y is None:
            verdict = "only in " + ("new" if x is None else "old")
            bad += 1
        elif x == y:
            verdict = "same"
        else:
            verdict = "DIFFERS at byte %d (%d vs %d bytes)" % (first_diff(x, y), len(x), len(y))
            bad += 1
        print("%-18s %-20s %12d  %s" % (k[0], k[1], len(x if x is not None else y), verdict))
    print("%d difference(s)" % bad)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
