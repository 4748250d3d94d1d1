#!/usr/bin/env bash
# fuzz_spec.sh -- fuzzes the spec validator and parsers (schema/: gp_schema_engine.c, gp_spec.c, gp_spec2d.c, gp_spec3d.c) with libFuzzer.
#
# Configures a build directory of its own with clang and -DGP_FUZZ=ON (every library under
# -fsanitize=fuzzer-no-link,address,undefined; the default gcc build is untouched), builds
# fuzz/fuzz_spec, copies the seed corpus fuzz/corpus into a work directory inside that build
# directory (the repository stays clean), and runs
#   fuzz_spec -runs=RUNS -max_len=65536 -dict=fuzz/spec.dict WORK fuzz/corpus
# Prints one line: executions, seconds, exec/s, corpus size, crashes found. A crash, leak or
# timeout stops the run; its input is saved under BUILD/artifacts/ and the script exits 1.
# Minimise one with: BUILD/fuzz/fuzz_spec -minimize_crash=1 -runs=100000 BUILD/artifacts/crash-...
# then put it into fuzz/regressions/ (tests/schema/test_spec_regressions.c replays that directory).
#
# usage: bench/fuzz_spec.sh [runs (1000000)]
# environment: GP_FUZZ_BUILD (build directory, default build-fuzz), GP_FUZZ_TIMEOUT (seconds one
# input may take, default 10), GP_FUZZ_SEED (libFuzzer -seed, default 1), CC (default clang).
# needs: clang (Debian package "clang"), cmake and the build dependencies of deploy/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-1000000}"
build="${GP_FUZZ_BUILD:-build-fuzz}"
timeout_s="${GP_FUZZ_TIMEOUT:-10}"
seed="${GP_FUZZ_SEED:-1}"
cc="${CC:-clang}"
command -v "$cc" >/dev/null || { echo "$cc not found (apt-get install clang)" >&2; exit 2; }

cfg_log="$(mktemp)"
CC="$cc" cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGP_FUZZ=ON >"$cfg_log" 2>&1 ||
  { cat "$cfg_log" >&2; rm -f "$cfg_log"; exit 2; }
rm -f "$cfg_log"
cmake --build "$build" -j"$(nproc 2>/dev/null || echo 2)" --target fuzz_spec >/dev/null

work="$build/corpus-work"
art="$build/artifacts"
log="$build/fuzz_spec.log"
rm -rf "$work" "$art"
mkdir -p "$work" "$art"
cp fuzz/corpus/* "$work/"
nseed=$(find fuzz/corpus -type f | wc -l)

t0=$(date +%s.%N)
set +e
ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}" UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1}" \
  "$build/fuzz/fuzz_spec" -runs="$runs" -max_len=65536 -dict=fuzz/spec.dict -seed="$seed" \
  -timeout="$timeout_s" -print_final_stats=1 -artifact_prefix="$art/" "$work" fuzz/corpus \
  >"$log" 2>&1
rc=$?
set -e
t1=$(date +%s.%N)

execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
slowest=$(sed -n 's/^stat::slowest_unit_time_sec: *//p' "$log" | tail -1)
rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
execs="${execs:-0}"
ncorpus=$(find "$work" -type f | wc -l)
ncrash=$(find "$art" -type f | wc -l)
awk -v e="$execs" -v t0="$t0" -v t1="$t1" -v c="$ncorpus" -v s="$nseed" -v k="$ncrash" \
    -v slow="${slowest:-?}" -v rss="${rss:-?}" 'BEGIN {
  t = t1 - t0;
  printf "fuzz_spec: %d executions, %.1f s, %.0f exec/s, corpus %d files (%d seeds + %d new), " \
         "crashes %d (slowest input %s s, peak RSS %s MB)\n", e, t, e / t, c, s, c - s, k, slow, rss }'
if [ "$rc" -ne 0 ] || [ "$ncrash" -ne 0 ]; then
  echo "fuzz_spec: libFuzzer exit $rc; log $log; inputs:" >&2
  find "$art" -type f >&2
  grep -m1 -A30 -E "ERROR: |contract broken|runtime error" "$log" >&2 || tail -30 "$log" >&2
  exit 1
fi
