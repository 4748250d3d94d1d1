"""The dashboard in a real browser (ctest it_test_dashboard_browser).

Starts grainpackd (gpd.py: 127.0.0.1 port 0, a temporary database) and runs
browser/dashboard.test.js in node, which drives Debian's chromium through puppeteer-core: it
submits both kinds through the form, opens each finished job, checks the summary against the
result and every view's picture, cancels a job through the page and reloads at #/jobs/{id}.
Screenshots go to $GP_SCREENSHOT_DIR (ctest: <build>/screenshots), else ./screenshots; their
paths are printed.

Needs node (>= 18), chromium and browser/node_modules (`npm ci` there), all installed by
`bash deploy/install-deps.sh --test`; if any is missing the test FAILS and says so (it does not
skip). GP_NODE and GP_CHROMIUM override the programs' paths. `--smoke` after the daemon's path
only loads the page and saves one screenshot (to check the set-up).
"""
import os
import re
import shutil
import signal
import subprocess
import sys

import gpd

HERE = os.path.dirname(os.path.abspath(__file__))
BROWSER_DIR = os.path.join(HERE, "browser")
SCRIPT = os.path.join(BROWSER_DIR, "dashboard.test.js")
SMOKE = "--smoke" in sys.argv[2:]
if SMOKE:
    sys.argv.remove("--smoke")
HINT = "install it with `bash deploy/install-deps.sh --test` (as root)"


def find_node():
    node = os.environ.get("GP_NODE") or shutil.which("node") or shutil.which("nodejs")
    if not node or not os.access(node, os.X_OK):
        raise AssertionError("node is not installed (Debian package nodejs; GP_NODE=%s); %s"
                             % (os.environ.get("GP_NODE", ""), HINT))
    out = subprocess.run([node, "--version"], capture_output=True, text=True, timeout=30)
    m = re.match(r"v(\d+)\.", out.stdout.strip())
    if out.returncode != 0 or not m:
        raise AssertionError("%s --version failed: %s %s" % (node, out.stdout, out.stderr))
    if int(m.group(1)) < 18:
        raise AssertionError("node %s is too old for puppeteer-core (needs >= 18)" % out.stdout.strip())
    return node


def find_chromium():
    path = os.environ.get("GP_CHROMIUM")
    if not path:
        for c in ("/usr/bin/chromium", shutil.which("chromium"), shutil.which("chromium-browser")):
            if c and os.access(c, os.X_OK):
                path = c
                break
    if not path or not os.access(path, os.X_OK):
        raise AssertionError("chromium is not installed (Debian package chromium; GP_CHROMIUM=%s); %s"
                             % (os.environ.get("GP_CHROMIUM", ""), HINT))
    return path


def check_modules():
    pkg = os.path.join(BROWSER_DIR, "node_modules", "puppeteer-core", "package.json")
    if not os.path.isfile(pkg):
        raise AssertionError("%s is missing: run `npm ci` in %s, or %s"
                             % (os.path.dirname(pkg), BROWSER_DIR, HINT))


def test_dashboard_browser(env):
    node = find_node()
    chromium = find_chromium()
    check_modules()
    out = os.path.abspath(os.environ.get("GP_SCREENSHOT_DIR") or "screenshots")
    os.makedirs(out, exist_ok=True)
    for f in os.listdir(out):  # this run's screenshots only
        if f.endswith((".png", ".svg")):
            os.remove(os.path.join(out, f))
    d = env.daemon(workers=2)
    cmd = [node, SCRIPT, "--url=" + d.url, "--out=" + out, "--chromium=" + chromium]
    if SMOKE:
        cmd.append("--smoke")
    print("running: " + " ".join(cmd), flush=True)
    limit = 480 * gpd.TIME_SCALE
    # chromium's own profile and crash files go to the test's temp dir
    run_env = dict(os.environ, HOME=env.dir, XDG_CONFIG_HOME=env.dir, XDG_CACHE_HOME=env.dir)
    # its own process group: a run past the limit is stopped with its chromium
    proc = subprocess.Popen(cmd, cwd=BROWSER_DIR, env=run_env, start_new_session=True)
    try:
        rc = proc.wait(limit)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise AssertionError("the browser test ran past %ds; screenshots in %s" % (limit, out))
    assert rc == 0, "the browser test failed (exit status %d); screenshots in %s" % (rc, out)
    assert d.stop() == 0, "the daemon did not stop cleanly"


if __name__ == "__main__":
    gpd.main([test_dashboard_browser])
