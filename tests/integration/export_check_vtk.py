"""export_check_vtk.py -- reads legacy VTK files with VTK's own vtkPolyDataReader and dumps what
the reader saw as JSON, for test_exports.py to compare with a job's result.

Runs under the interpreter that has VTK (Debian python3-vtk9: /usr/bin/python3), not under the
test's python3:

    /usr/bin/python3 export_check_vtk.py OUT.json FILE.vtk [FILE.vtk ...]

OUT.json is a list with one object per file:
    {"file", "errors": [messages VTK reported], "points": [[x, y, z], ...],
     "verts": [[ids], ...], "polys": [[ids], ...], "lines": n, "strips": n, "cells": n,
     "point_data" / "cell_data" / "field_data": {name: {"type", "components", "values": [...]}}}
Values are Python floats/ints, so json writes them exactly (shortest round-trip repr).
"""
import json
import os
import sys
import tempfile

import vtk


def cells(ca):
    out = []
    ids = vtk.vtkIdList()
    ca.InitTraversal()
    while ca.GetNextCell(ids):
        out.append([ids.GetId(k) for k in range(ids.GetNumberOfIds())])
    return out


def arrays(data):
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetAbstractArray(i)
        nc = a.GetNumberOfComponents()
        vals = []
        if isinstance(a, vtk.vtkDataArray):
            conv = float if a.GetDataType() in (vtk.VTK_FLOAT, vtk.VTK_DOUBLE) else int
            for t in range(a.GetNumberOfTuples()):
                vals.extend(conv(a.GetComponent(t, c)) for c in range(nc))
        out[a.GetName()] = {"type": a.GetDataTypeAsString(), "components": nc, "values": vals}
    return out


class Messages:
    """Everything VTK reports goes to a file (the legacy reader's ASCII parse errors are generic
    warnings that no observer of the reader sees); read back after each file."""

    def __init__(self):
        fd, self.path = tempfile.mkstemp(prefix="vtk-messages-", suffix=".txt")
        os.close(fd)
        w = vtk.vtkFileOutputWindow()
        w.SetFileName(self.path)
        w.SetFlush(1)
        w.SetAppend(1)
        vtk.vtkOutputWindow.SetInstance(w)
        self.window = w
        self.seen = 0

    def new(self):
        with open(self.path, errors="replace") as f:
            text = f.read()
        out, self.seen = text[self.seen:], len(text)
        return [line for line in out.splitlines() if line.strip()]

    def close(self):
        os.unlink(self.path)


MESSAGES = None


def read(path):
    errors = []
    r = vtk.vtkPolyDataReader()
    r.AddObserver("ErrorEvent", lambda o, e: errors.append("error in " + path))
    r.AddObserver("WarningEvent", lambda o, e: errors.append("warning in " + path))
    r.SetFileName(path)
    r.ReadAllScalarsOn()
    r.ReadAllVectorsOn()
    r.ReadAllFieldsOn()
    if not r.IsFilePolyData():
        errors.append("%s: vtkPolyDataReader says this is not polydata" % path)
    r.Update()
    p = r.GetOutput()
    pts = p.GetPoints()
    errors += MESSAGES.new()
    return {
        "file": path,
        "errors": errors,
        "points": [list(pts.GetPoint(i)) for i in range(pts.GetNumberOfPoints())] if pts else [],
        "verts": cells(p.GetVerts()),
        "polys": cells(p.GetPolys()),
        "lines": p.GetNumberOfLines(),
        "strips": p.GetNumberOfStrips(),
        "cells": p.GetNumberOfCells(),
        "point_data": arrays(p.GetPointData()),
        "cell_data": arrays(p.GetCellData()),
        "field_data": arrays(p.GetFieldData()),
    }


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: export_check_vtk.py OUT.json FILE.vtk [...]")
    global MESSAGES
    MESSAGES = Messages()
    try:
        out = [read(f) for f in sys.argv[2:]]
    finally:
        MESSAGES.close()
    with open(sys.argv[1], "w") as f:
        json.dump(out, f)


if __name__ == "__main__":
    main()
