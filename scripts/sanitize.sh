#!/usr/bin/env bash
# scripts/sanitize.sh [address|thread]
#   address (default, in CI): builds SSTA with AddressSanitizer + UndefinedBehaviorSanitizer
#     (and LeakSanitizer) in build-asan/ and runs the whole test suite there; any sanitizer
#     report fails a test.
#   thread (also in CI): builds with ThreadSanitizer in build-tsan/ and runs the tests that run
#     threads (pipelined build-map and its CLI, online refinement, concurrent queries, the stereo
#     and frame pipelines called from several threads); any race report fails the script. The
#     test binaries run two at a time, each with its own threads.
# Both build without the Python module: an instrumented extension needs the sanitizer's runtime
# preloaded into the interpreter, and Debian 12's python3.11 dies at start with libtsan.so.2
# preloaded (a segfault before `print`). Python's GIL release is tested in scripts/test.sh
# (test_query_releases_the_gil, concurrent queries); the C++ it runs unlocked is under TSan here
# (mapping_test's concurrent queries).
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
    # Two accuracy runs of many frames are left to the Release suite, as end_to_end_test is
    # (tests/end_to_end/tests.cmake): a 20-frame refinement against an error-free map and
    # oracle labels over a rendered yard. The short cases of both suites run here.
    OPENCV_FOR_THREADS_NUM=1 \
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --output-on-failure -j "$jobs" \
        -E '^pipeline_test[.](OnlineRefinement[.]MapMatches|BuildMap[.]OracleLabels)'
    ;;
  thread)
    build_dir=${BUILD_DIR:-build-tsan}
    cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSSTA_SANITIZE_THREAD=ON -DSSTA_BUILD_TESTS=ON \
      -DSSTA_BUILD_PYTHON=OFF
    cmake --build "$build_dir" -j "$jobs" --target ssta_cli pipeline_test cli_test sensors_test mapping_test stereo_test
    cd "$build_dir"
    # GDAL (loaded by OpenCV's image codecs) takes its own locks in an order TSan flags: suppressed.
    export TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/../tests/tsan.supp"
    # OpenCV's parallel_for_ runs on Debian's TBB, which is not instrumented: TSan cannot see its
    # hand-over and join, and reports every loop body's data as racing with the calling thread.
    # So OpenCV runs one thread here (tests/opencv_threads.cpp and the CLI read this), and TSan
    # judges the threads SSTA starts itself: the pipelined build's reader, analysis and fusion
    # stages, and the matchers, frame pipelines and map queries the tests call from several
    # std::threads at once.
    export OPENCV_FOR_THREADS_NUM=1
    export TMPDIR=$PWD/test-tmp
    mkdir -p "$TMPDIR"
    # The two accuracy runs (a 20-frame refinement against an error-free map, oracle labels over
    # a rendered yard) are left to the Release suite: their threads are the pipelined
    # build's, which the short BuildMap and OnlineRefinementShort cases run too.
    (
      ./tests/pipeline_test --gtest_brief=1 \
        --gtest_filter='BuildMap.*:OnlineRefinementShort.*:OnlineRefinement.Euroc*:FramePipeline.*:FrameAnalyzer.*-BuildMap.OracleLabels*'
      ./tests/sensors_test --gtest_brief=1 --gtest_filter='GravityTrack.*'
      ./tests/stereo_test --gtest_brief=1 --gtest_filter='*Concurrent*'
    ) &
    first=$!
    status=0
    ./tests/cli_test --gtest_brief=1 --gtest_filter='Cli.*' || status=$?
    ./tests/mapping_test --gtest_brief=1 || status=$?
    wait "$first" || status=$?
    exit "$status"
    ;;
  *)
    echo "usage: scripts/sanitize.sh [address|thread]" >&2
    exit 2
    ;;
esac
