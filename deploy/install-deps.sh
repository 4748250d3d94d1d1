#!/usr/bin/env bash
# Installs the Debian packages grainpack builds against. With --test, also the tools its tests
# use: the DEM programs lammps (with openmpi-bin: mpirun runs the lammps-relax script on 2
# ranks), liggghts and yade, and VTK's Python reader, which prove that the export files load,
# node (the dashboard's script) and promtool (package prometheus: checks the /metrics text),
# postgresql (initdb, pg_ctl, psql: the it_pg_* tests start a server of their own; the
# package's own cluster is not used), voro++-dev (the reference test_voronoi3d_voro compares
# gp_voronoi3d with),
# and for the dashboard's browser test chromium, npm and then, by `npm ci` in
# tests/integration/browser/, puppeteer-core as pinned in its package-lock.json (tests/run.sh
# passes --test). npm runs as the user running this script; only apt-get goes through sudo.
# Idempotent; needs root (or sudo). Usage: bash deploy/install-deps.sh [--test]
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
PKGS="build-essential cmake pkg-config \
  libmicrohttpd-dev libjansson-dev libsqlite3-dev libpq-dev libfftw3-dev libgsl-dev \
  python3 curl wrk"
TEST=0
if [ "${1:-}" = "--test" ]; then
  TEST=1
  PKGS="$PKGS lammps openmpi-bin liggghts yade python3-vtk9 nodejs prometheus chromium fonts-dejavu-core \
    postgresql voro++-dev"
fi
missing=""
for p in $PKGS; do
  dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
done
# Debian's nodejs comes without npm (package npm); a nodejs that bundles npm (NodeSource) conflicts
# with that package, so it is only asked for when there is no npm at all.
if [ "$TEST" = 1 ] && ! command -v npm >/dev/null 2>&1; then
  missing="$missing npm"
fi
if [ -n "$missing" ]; then
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends $missing
fi
if [ "$TEST" = 1 ]; then
  # The browser test's node_modules, next to its script (found from there wherever the clone is);
  # again only when package-lock.json changed since the last `npm ci`.
  browser="$(cd "$(dirname "$0")/../tests/integration/browser" && pwd)"
  if ! cmp -s "$browser/package-lock.json" "$browser/node_modules/.grainpack-lock.json"; then
    (cd "$browser" && npm ci --no-audit --no-fund --ignore-scripts)
    cp "$browser/package-lock.json" "$browser/node_modules/.grainpack-lock.json"
  fi
fi
