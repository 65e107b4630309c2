#!/usr/bin/env bash
# scripts/sanitize.sh [address|thread]
#   address (default, in CI): builds SSTA with AddressSanitizer + UndefinedBehaviorSanitizer
#     (and LeakSanitizer) in build-asan/ and runs the whole test suite there; any sanitizer
#     report fails a test.
#   thread: builds with ThreadSanitizer in build-tsan/ and runs the tests that run threads
#     (pipelined build-map and its CLI, online refinement, concurrent queries, the stereo and
#     frame pipelines called from several threads); any race report fails a test. Not in CI
#     (a second full build): run it after touching the pipelined build or the map's readers.
# Both build without the Python module: an instrumented extension would need the sanitizer's
# runtime preloaded into the Python interpreter (python/tests run in scripts/test.sh).
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-address}
bash scripts/install-deps.sh
jobs=${JOBS:-2}
case "$mode" in
  address)
    build_dir=${BUILD_DIR:-build-asan}
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSSTA_SANITIZE=ON -DSSTA_BUILD_TESTS=ON \
      -DSSTA_BUILD_PYTHON=OFF
    cmake --build "$build_dir" -j "$jobs"
    cd "$build_dir"
    # One OpenCV thread per test process: ctest runs $jobs processes at once, and each one
    # fanning out over every core (the matcher, the normals' bands, the concurrent analysis
    # steps) oversubscribes them under the sanitizers' 3-5x slowdown (two map tests went past
    # their timeout). The split steps still run, one after the other; races are TSan's.
    OPENCV_FOR_THREADS_NUM=1 \
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --output-on-failure -j "$jobs"
    ;;
  thread)
    build_dir=${BUILD_DIR:-build-tsan}
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSSTA_SANITIZE_THREAD=ON -DSSTA_BUILD_TESTS=ON \
      -DSSTA_BUILD_PYTHON=OFF
    cmake --build "$build_dir" -j "$jobs" --target ssta_cli pipeline_test cli_test sensors_test mapping_test stereo_test
    cd "$build_dir"
    # GDAL (loaded by OpenCV's image codecs) takes its own locks in an order TSan flags: suppressed.
    export TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/../tests/tsan.supp"
    ./tests/pipeline_test --gtest_filter='BuildMap.*:OnlineRefinement*:FramePipeline.*'
    ./tests/cli_test --gtest_filter='Cli.*'
    ./tests/sensors_test --gtest_filter='GravityTrack.*'
    ./tests/mapping_test
    ./tests/stereo_test --gtest_filter='*Concurrent*'
    ;;
  *)
    echo "usage: scripts/sanitize.sh [address|thread]" >&2
    exit 2
    ;;
esac
