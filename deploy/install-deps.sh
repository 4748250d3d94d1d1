#!/usr/bin/env bash
# Installs the Debian packages grainpack builds against (and the tools its tests use).
# Idempotent; needs root (or sudo). Usage: bash deploy/install-deps.sh
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
PKGS="build-essential cmake pkg-config \
  libmicrohttpd-dev libjansson-dev libsqlite3-dev libfftw3-dev libgsl-dev \
  python3 curl wrk"
missing=""
for p in $PKGS; do
  dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
done
if [ -n "$missing" ]; then
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends $missing
fi
