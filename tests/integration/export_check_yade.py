"""export_check_yade.py -- imports grainpack's yade exports into YADE with ymport and dumps what
YADE built as JSON, for test_exports.py to compare with a job's result. Run inside YADE:

    yade -n -x export_check_yade.py OUT.json 3d:FILE.txt 2d:FILE.txt ...

3d files go through ymport.text (appended to the scene), 2d files through ymport.textClumps
(which appends the clumps itself). The scene is reset before each file. OUT.json is a list
with one object per file:
    3d: {"file", "dim": 3, "bodies": n, "spheres": [[x, y, z, r], ...]}
    2d: {"file", "dim": 2, "bodies": n, "spheres": n, "clumps": n,
         "members": [[[x, y, z, r], ...] per clump, in textClumps' order]}
OUT.json is written only when every file imported. The script removes the temporary directory
YADE leaves in /tmp.
"""
import json
import os
import shutil
import sys

from yade import ymport
from yade.wrapper import Sphere


def sphere_row(b):
    p = b.state.pos
    return [float(p[0]), float(p[1]), float(p[2]), float(b.shape.radius)]


def main():
    out_path, files = sys.argv[1], sys.argv[2:]
    out = []
    for arg in files:
        kind, path = arg.split(":", 1)
        O.reset()  # noqa: F821 -- O is YADE's global Omega
        if kind == "3d":
            bodies = ymport.text(path)
            O.bodies.append(bodies)  # noqa: F821
            out.append({"file": path, "dim": 3, "bodies": len(O.bodies),  # noqa: F821
                        "spheres": [sphere_row(b) for b in O.bodies  # noqa: F821
                                    if isinstance(b.shape, Sphere)]})
        elif kind == "2d":
            clumps = ymport.textClumps(path)
            bs = O.bodies  # noqa: F821
            out.append({"file": path, "dim": 2, "bodies": len(bs),
                        "spheres": sum(1 for b in bs if isinstance(b.shape, Sphere)),
                        "clumps": sum(1 for b in bs if b.isClump),
                        "members": [[sphere_row(bs[m]) for m in mids] for _, mids in clumps]})
        else:
            raise SystemExit("unknown kind %r (expected 3d: or 2d:)" % kind)
    with open(out_path, "w") as f:
        json.dump(out, f)
    print("export_check_yade: %d files imported" % len(out))


def remove_yade_tmp_dir():
    """YADE makes /tmp/yade-XXXXXX at start-up and leaves it behind after `-x`: remove ours."""
    d = os.path.dirname(O.tmpFilename())  # noqa: F821
    if os.path.basename(d).startswith("yade-"):
        shutil.rmtree(d, ignore_errors=True)


try:
    main()
finally:
    remove_yade_tmp_dir()
