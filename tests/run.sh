#!/usr/bin/env bash
# The whole test suite, from a fresh Debian machine: install the dependencies, then build and
# run every ctest twice -- a Release build, and a Debug build under AddressSanitizer +
# UndefinedBehaviorSanitizer (leak checking on). Exits non-zero if any test fails.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install-deps.sh --test
jobs=$(nproc 2>/dev/null || echo 2)

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$jobs"
ctest --test-dir build --output-on-failure -j"$jobs"

# The sanitized build runs the core 2-3x slower, and two daemons share the cores (-j): the
# integration tests' latency limits are doubled there (GPD_TEST_TIME_SCALE, gpd.py); the
# Release pass above holds them as they are.
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGP_SANITIZE=ON
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  GPD_TEST_TIME_SCALE=2 ctest --test-dir build-asan --output-on-failure -j"$jobs"
