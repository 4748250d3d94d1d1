#!/usr/bin/env python3
"""test_house.py -- the layout rules of the source tree, checked on the tree itself.

    python3 tests/house/test_house.py <repository root> <libgpd.a>

1. No include cycle among the modules of server/, schema/ and core/ (a module is a .c and its
   .h, with its private header x_internal.h or x_impl.h: the node "x"; an edge x -> y when a
   file of x includes a header of y).
2. No issue reference ("issue #N", "#N)") and no commit hash in the comments of core/, server/
   and schema/: the code says what it does; its history belongs to git and docs/design/.
3. Every global symbol that the server library defines starts with gp_, gpd_ or the name of
   its own module (its object file's name).
4. A kind's name (a folder of schema/kinds/), as a string, appears in server/ and schema/ only
   inside that kind's own folders (kinds/<kind>/).
Prints each violation and "N passed, N failed" at the end; exits 1 when any check failed.
"""
import os
import re
import subprocess
import sys

ROOT = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.getcwd()
LIB = sys.argv[2] if len(sys.argv) > 2 else None
results = {"passed": 0, "failed": 0}


def check(ok, what):
    results["passed" if ok else "failed"] += 1
    if not ok:
        print("FAIL:", what)


def sources(top, exts=(".c", ".h")):
    for d, _, files in os.walk(os.path.join(ROOT, top)):
        for f in sorted(files):
            if f.endswith(exts):
                yield os.path.join(d, f)


INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def module_of(path):
    return re.sub(r"_(internal|impl)$", "", os.path.splitext(os.path.basename(path))[0])


def include_graph(tops):
    """module name -> set of module names it includes (headers found in the given trees)"""
    paths = [p for t in tops for p in sources(t)]
    known = {module_of(p) for p in paths}
    graph = {}
    for p in paths:
        me = module_of(p)
        for inc in INCLUDE.findall(open(p, encoding="utf-8").read()):
            other = module_of(inc)
            if other != me and other in known:
                graph.setdefault(me, set()).add(other)
    return graph


def cycles(graph):
    """the strongly connected components of more than one module (Tarjan)"""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def check_cycles():
    graph = include_graph(["server", "schema", "core"])
    found = cycles(graph)
    check(not found, "include cycles: %s" % found)
    # the test sees a cycle when there is one: a graph with a known cycle
    check(cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == [["a", "b", "c"]], "cycle finder")


COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)
HISTORY = [re.compile(r"issue\s*#\s*\d+", re.I), re.compile(r"#\d+\)"),
           re.compile(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,12}\b")]


def check_history():
    bad = []
    for top in ("core", "server", "schema"):
        for p in sources(top):
            if p.endswith("_table.h"):  # generated numeric tables
                continue
            text = open(p, encoding="utf-8").read()
            for m in COMMENT.finditer(text):
                for h in HISTORY:
                    for hit in h.finditer(m.group(0)):
                        line = text.count("\n", 0, m.start() + hit.start()) + 1
                        bad.append("%s:%d: %s" % (os.path.relpath(p, ROOT), line, hit.group(0)))
    for b in bad:
        print("  history in a comment:", b)
    check(not bad, "%d issue references or commit hashes in comments" % len(bad))


def check_symbols():
    if not LIB:
        print("no library given: symbol names not checked")
        check(False, "the server library's path")
        return
    out = subprocess.run(["nm", "-g", "--defined-only", "-A", LIB], capture_output=True,
                         text=True, check=True).stdout
    bad, n = [], 0
    for line in out.splitlines():
        parts = line.split()
        if len(parts) != 3:
            continue
        obj = parts[0].split(":")[-2] if parts[0].count(":") >= 2 else parts[0]
        module = os.path.basename(obj).split(".")[0]
        sym = parts[2]
        if sym.startswith("__"):  # the compiler's and sanitizers' own (__odr_asan.*): reserved
            continue
        n += 1
        if not (sym.startswith(("gp_", "gpd_")) or sym.startswith(module)):
            bad.append("%s: %s" % (module, sym))
    for b in bad:
        print("  global name after no module:", b)
    check(n > 100, "the library's global symbols were read (%d)" % n)
    check(not bad, "%d global names after no module" % len(bad))


def kind_names():
    """the kinds, by their folders in schema/kinds/"""
    return sorted(os.listdir(os.path.join(ROOT, "schema", "kinds")))


def check_kind_names():
    kinds = kind_names()
    check(len(kinds) >= 2, "the kinds' folders were found (%s)" % kinds)
    KIND_NAME = re.compile('"(%s)"' % "|".join(map(re.escape, kinds)))
    bad = []
    for top in ("server", "schema"):
        for d, _, files in os.walk(os.path.join(ROOT, top)):
            for f in files:
                p = os.path.join(d, f)
                rel = os.path.relpath(p, ROOT)
                try:
                    text = open(p, encoding="utf-8").read()
                except UnicodeDecodeError:
                    continue
                for m in KIND_NAME.finditer(text):
                    if ("/kinds/%s/" % m.group(1)) not in "/" + rel.replace(os.sep, "/"):
                        line = text.count("\n", 0, m.start()) + 1
                        bad.append("%s:%d: %s" % (rel, line, m.group(0)))
    for b in bad:
        print("  kind name outside its folder:", b)
    check(not bad, "%d kind names outside their kinds' folders" % len(bad))


check_cycles()
check_history()
check_symbols()
check_kind_names()
print("%d passed, %d failed" % (results["passed"], results["failed"]))
sys.exit(1 if results["failed"] else 0)
