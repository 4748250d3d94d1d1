#!/usr/bin/env bash
# poller_bench.sh -- load test of grainpackd's status endpoint with wrk.
#
# Starts the daemon on 127.0.0.1 (free port, temp database), submits jobs so that workers are
# busy while the load runs, and hits GET /v1/jobs/{id} (and a few other read endpoints) with
# wrk, 200 connections. Prints requests/s and latency percentiles as a table.
#
# usage: bench/load/poller_bench.sh [path/to/grainpackd] [seconds per run (10)] [connections (200)]
# needs: wrk (Debian package "wrk"), curl, python3.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${1:-$here/../../build/server/grainpackd}"
dur="${2:-10}"
conns="${3:-200}"
threads="${WRK_THREADS:-2}"
workers="${GPD_WORKERS:-1}"
command -v wrk >/dev/null || { echo "wrk not found (apt-get install wrk)" >&2; exit 2; }
[ -x "$bin" ] || { echo "no grainpackd at $bin" >&2; exit 2; }

tmp="$(mktemp -d)"
pid=""
cleanup() {
  if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid"; wait "$pid" 2>/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT INT TERM

ulimit -n 65536 2>/dev/null || true
"$bin" --listen 127.0.0.1:0 --db "$tmp/bench.db" --workers "$workers" \
  --log-level warn >"$tmp/out" 2>"$tmp/err" &
pid=$!
for _ in $(seq 100); do grep -q "^listening on " "$tmp/out" 2>/dev/null && break; sleep 0.1; done
url="$(head -1 "$tmp/out" | sed 's/^listening on //')"
[ -n "$url" ] || { echo "daemon did not start:" >&2; cat "$tmp/err" >&2; exit 1; }

submit() {
  curl -sf -X POST "$url/v1/jobs" -H 'Content-Type: application/json' -d "$1" |
    python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])'
}
small='{"kind":"fourier-voronoi-2d","seed":1,"particles":60,"contour_points":32,"imc":{"threshold":0.05,"max_steps":20000}}'
long='{"kind":"fourier-voronoi-2d","seed":2,"particles":40000,"contour_points":64,"imc":{"threshold":1e-9,"max_steps":1000000000}}'
done_id="$(submit "$small")"
for _ in $(seq 200); do
  st="$(curl -sf "$url/v1/jobs/$done_id" | python3 -c 'import json,sys; print(json.load(sys.stdin)["status"])')"
  case "$st" in succeeded|failed|cancelled) break;; esac; sleep 0.1
done
run_id="$(submit "$long")"     # keeps a worker busy (and writing progress) during the load
for i in $(seq 20); do submit "$small" >/dev/null; done   # a queue behind it

printf "grainpackd load test: %s, wrk -t%s -c%s -d%ss, %s worker(s), %s cores\n" \
  "$url" "$threads" "$conns" "$dur" "$workers" "$(nproc)"
printf "%-34s %12s %10s %10s %10s %8s\n" "endpoint" "requests/s" "p50 ms" "p99 ms" "max ms" "errors"
bench() {
  local name="$1" path="$2" line
  line="$(wrk -t"$threads" -c"$conns" -d"${dur}s" --timeout 10s -s "$here/report.lua" "$url$path" |
          grep '^RESULT')"
  python3 - "$name" "$line" <<'PY'
import sys
name, line = sys.argv[1], sys.argv[2]
kv = dict(x.split("=") for x in line.split()[1:])
rps = float(kv["requests"]) / (float(kv["duration_us"]) / 1e6)
errs = int(kv["errors"]) + int(kv["non2xx"])
print("%-34s %12.0f %10.2f %10.2f %10.2f %8d" % (name, rps, float(kv["p50"]) / 1e3,
      float(kv["p99"]) / 1e3, float(kv["max"]) / 1e3, errs))
PY
}
bench "GET /v1/jobs/{id} (running)" "/v1/jobs/$run_id"
bench "GET /v1/jobs/{id} (succeeded)" "/v1/jobs/$done_id"
bench "GET /v1/health" "/v1/health"
bench "GET /v1/jobs?limit=20" "/v1/jobs?limit=20"
curl -sf -X DELETE "$url/v1/jobs/$run_id" >/dev/null || true
