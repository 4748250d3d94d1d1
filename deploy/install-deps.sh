#!/usr/bin/env bash
# Installs the Debian packages grainpack builds against. With --test, also the tools its tests
# use: the DEM programs lammps, liggghts and yade, and VTK's Python reader, which prove that the
# export files load, node (the dashboard's script) and promtool (package prometheus: checks the
# /metrics text) (tests/run.sh passes it).
# Idempotent; needs root (or sudo). Usage: bash deploy/install-deps.sh [--test]
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
PKGS="build-essential cmake pkg-config \
  libmicrohttpd-dev libjansson-dev libsqlite3-dev libfftw3-dev libgsl-dev \
  python3 curl wrk"
if [ "${1:-}" = "--test" ]; then
  PKGS="$PKGS lammps liggghts yade python3-vtk9 nodejs prometheus"
fi
missing=""
for p in $PKGS; do
  dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
done
if [ -n "$missing" ]; then
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends $missing
fi
