#!/usr/bin/env bash
# Builds SSTA with AddressSanitizer + UndefinedBehaviorSanitizer (and LeakSanitizer) in
# build-asan/ and runs the whole test suite there; any sanitizer report fails a test.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
build_dir=${BUILD_DIR:-build-asan}
jobs=${JOBS:-2}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSSTA_SANITIZE=ON -DSSTA_BUILD_TESTS=ON
cmake --build "$build_dir" -j "$jobs"
cd "$build_dir"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --output-on-failure -j "$jobs"
