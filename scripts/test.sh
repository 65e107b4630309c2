#!/usr/bin/env bash
# Builds SSTA and runs the whole test suite. Installs the Debian packages it needs first (as root
# or with sudo), so this one command works on a fresh Debian 12 machine. The Google Benchmark
# cases are built too and run once as a smoke test (stage_benchmark_smoke), so they cannot rot.
#   scripts/test.sh                 # Release build in build/, all tests
#   BUILD_DIR=build-x scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
build_dir=${BUILD_DIR:-build}
jobs=${JOBS:-2}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSSTA_BUILD_TESTS=ON -DSSTA_BUILD_BENCHMARKS=ON ${CMAKE_ARGS:-}
cmake --build "$build_dir" -j "$jobs"
cd "$build_dir"
ctest --output-on-failure -j "$jobs"
