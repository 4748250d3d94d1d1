#!/usr/bin/env bash
# fuzz.sh -- runs one libFuzzer target of fuzz/ for a number of inputs and prints what it did.
#
# Targets (fuzz/CMakeLists.txt):
#   spec      the spec validator and parsers (schema/); seeds: the files at the top of
#             fuzz/corpus/, dictionary fuzz/spec.dict
#   pgm       the PGM reader and the tracer (core/2d/gp_trace.c); seeds fuzz/corpus/pgm/,
#             dictionary fuzz/pgm.dict; run with a 64 MB malloc limit, so that a header that
#             makes the reader allocate for pixels the input does not hold is a crash
#   outlines  the JSON outlines reader and the outline analysis (shape.outlines and
#             POST /v1/shapes/analyze); seeds fuzz/corpus/outlines/, dictionary
#             fuzz/outlines.dict; inputs up to 16 KiB (a few hundred outlines: larger sets add
#             time per input, not paths)
#
# Configures a build directory of its own with clang and -DGP_FUZZ=ON (every library under
# -fsanitize=fuzzer-no-link,address,undefined; the default gcc build is untouched), builds
# fuzz/fuzz_<target>, copies the target's seeds into a work directory inside that build
# directory (the repository stays clean), and runs
#   fuzz_<target> -runs=RUNS -max_len=... -dict=... WORK
# Prints one line: executions, seconds, exec/s, coverage (libFuzzer's cov: edges and ft:
# features), corpus size, crashes found. A crash, leak or timeout stops the run; its input is
# saved under BUILD/artifacts-<target>/ and the script exits 1. Minimise one with
#   BUILD/fuzz/fuzz_<target> -minimize_crash=1 -runs=100000 BUILD/artifacts-<target>/crash-...
# then put it into fuzz/regressions/ (spec) or fuzz/regressions/<target>/; the ctests
# test_spec_regressions, test_trace_regressions and test_spec_outline_regressions replay them.
#
# usage: bench/fuzz.sh spec|pgm|outlines [runs (1000000)]
# environment: GP_FUZZ_BUILD (build directory, default build-fuzz), GP_FUZZ_TIMEOUT (seconds one
# input may take, default 10), GP_FUZZ_SEED (libFuzzer -seed, default 1), CC (default clang).
# needs: clang (Debian package "clang"), cmake and the build dependencies of deploy/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${1:-}"
runs="${2:-1000000}"
case "$target" in
  spec) seeds=fuzz/corpus; dict=fuzz/spec.dict; max_len=65536; extra=() ;;
  pgm) seeds=fuzz/corpus/pgm; dict=fuzz/pgm.dict; max_len=65536; extra=(-malloc_limit_mb=64) ;;
  outlines) seeds=fuzz/corpus/outlines; dict=fuzz/outlines.dict; max_len=16384; extra=() ;;
  *) echo "usage: $0 spec|pgm|outlines [runs]" >&2; exit 2 ;;
esac
build="${GP_FUZZ_BUILD:-build-fuzz}"
timeout_s="${GP_FUZZ_TIMEOUT:-10}"
seed="${GP_FUZZ_SEED:-1}"
cc="${CC:-clang}"
command -v "$cc" >/dev/null || { echo "$cc not found (apt-get install clang)" >&2; exit 2; }

cfg_log="$(mktemp)"
CC="$cc" cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGP_FUZZ=ON >"$cfg_log" 2>&1 ||
  { cat "$cfg_log" >&2; rm -f "$cfg_log"; exit 2; }
rm -f "$cfg_log"
cmake --build "$build" -j"$(nproc 2>/dev/null || echo 2)" --target "fuzz_$target" >/dev/null

work="$build/corpus-$target"
art="$build/artifacts-$target"
log="$build/fuzz_$target.log"
rm -rf "$work" "$art"
mkdir -p "$work" "$art"
# the seeds are the folder's own files: the spec target's folder holds the others' folders
find "$seeds" -maxdepth 1 -type f ! -name '.*' -exec cp {} "$work/" \;
nseed=$(find "$work" -type f | wc -l)

t0=$(date +%s.%N)
set +e
ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}" UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1}" \
  "$build/fuzz/fuzz_$target" -runs="$runs" -max_len="$max_len" -dict="$dict" -seed="$seed" \
  -timeout="$timeout_s" "${extra[@]}" -print_final_stats=1 -artifact_prefix="$art/" "$work" \
  >"$log" 2>&1
rc=$?
set -e
t1=$(date +%s.%N)

execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
slowest=$(sed -n 's/^stat::slowest_unit_time_sec: *//p' "$log" | tail -1)
rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | tr -dc 0-9)
ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | tr -dc 0-9)
execs="${execs:-0}"
ncorpus=$(find "$work" -type f | wc -l)
ncrash=$(find "$art" -type f | wc -l)
awk -v n="fuzz_$target" -v e="$execs" -v t0="$t0" -v t1="$t1" -v c="$ncorpus" -v s="$nseed" \
    -v k="$ncrash" -v cov="${cov:-?}" -v ft="${ft:-?}" -v slow="${slowest:-?}" \
    -v rss="${rss:-?}" 'BEGIN {
  t = t1 - t0;
  printf "%s: %d executions, %.1f s, %.0f exec/s, cov %s ft %s, corpus %d files " \
         "(%d seeds + %d new), crashes %d (slowest input %s s, peak RSS %s MB)\n", n, e, t,
         e / t, cov, ft, c, s, c - s, k, slow, rss }'
if [ "$rc" -ne 0 ] || [ "$ncrash" -ne 0 ]; then
  echo "fuzz_$target: libFuzzer exit $rc; log $log; inputs:" >&2
  find "$art" -type f >&2
  grep -m1 -A30 -E "ERROR: |contract broken|runtime error|malloc limit" "$log" >&2 ||
    tail -30 "$log" >&2
  exit 1
fi
