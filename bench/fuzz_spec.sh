#!/usr/bin/env bash
# fuzz_spec.sh -- fuzzes the spec validator and parsers (schema/: gp_schema_engine.c, gp_spec.c,
# the kinds' readers) with libFuzzer: bench/fuzz.sh spec, which builds fuzz/fuzz_spec in
# build-fuzz/ with clang, runs it from the seeds at the top of fuzz/corpus/ with fuzz/spec.dict
# and prints executions, seconds, exec/s, coverage, corpus size and crashes (see fuzz.sh for
# the environment and what to do with a crash: its minimised input goes into fuzz/regressions/,
# which tests/schema/test_spec_regressions.c replays).
#
# usage: bench/fuzz_spec.sh [runs (1000000)]
set -euo pipefail
exec "$(dirname "$0")/fuzz.sh" spec "$@"
