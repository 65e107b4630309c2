#!/usr/bin/env bash
# Builds SSTA and runs the whole test suite. Installs the Debian packages it needs first (as root
# or with sudo), so this one command works on a fresh Debian 12 machine. The Google Benchmark
# cases are built too and run once as a smoke test (stage_benchmark_smoke), so they cannot rot.
# After CTest, pytest runs the Python API's tests (python/tests) against the same build.
#   scripts/test.sh                 # Release build in build/, all tests
#   BUILD_DIR=build-x scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
build_dir=${BUILD_DIR:-build}
jobs=${JOBS:-2}
# SSTA_BUILD_PYTHON=ON: the Python API is part of what CI checks, so a missing dependency fails
# here instead of quietly leaving its tests out.
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSSTA_BUILD_TESTS=ON -DSSTA_BUILD_BENCHMARKS=ON \
  -DSSTA_BUILD_PYTHON=ON ${CMAKE_ARGS:-}
cmake --build "$build_dir" -j "$jobs"
(cd "$build_dir" && ctest --output-on-failure -j "$jobs")

# The interpreter CMake built the module for (it has NumPy; the first python3 on PATH may not).
python=$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build_dir/CMakeCache.txt")
# No .pytest_cache or __pycache__ in the source tree.
PYTHONDONTWRITEBYTECODE=1 SSTA_BUILD_DIR="$build_dir" PYTHONPATH="$build_dir/python" \
  "$python" -m pytest -q -p no:cacheprovider python/tests
