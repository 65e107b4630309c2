#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang, ASan + UBSan) in build-fuzz/ and runs each for a
# bounded time on its seed corpus (fuzz/corpus/<target>/). Any crash, sanitizer report, leak,
# uncaught exception, timeout or out-of-memory fails the script; the reproducer is left in
# build-fuzz/artifacts/<target>/.
#   scripts/fuzz.sh            # 30 s per target
#   scripts/fuzz.sh 300        # 5 minutes per target
#   FUZZ_TARGETS="config map_file" scripts/fuzz.sh 60
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-30}
bash scripts/install-deps.sh
build_dir=${BUILD_DIR:-build-fuzz}
jobs=${JOBS:-2}
targets=${FUZZ_TARGETS:-asl_csv kitti_text sensor_yaml config map_file mcap ros_messages image_codec}

cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DSSTA_BUILD_FUZZERS=ON -DSSTA_BUILD_APPS=OFF -DSSTA_BUILD_TESTS=OFF >/dev/null
cmake --build "$build_dir" -j "$jobs" --target ssta_fuzzers

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
status=0
for t in $targets; do
  work="$build_dir/corpus/$t"       # grows during the run; the seeds in fuzz/ stay untouched
  artifacts="$build_dir/artifacts/$t/"
  mkdir -p "$work" "$artifacts"
  log="$build_dir/fuzz_$t.log"
  echo "fuzz: $t for ${seconds} s"
  if "$build_dir/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=16384 \
      -print_final_stats=1 -artifact_prefix="$artifacts" "$work" "fuzz/corpus/$t" >"$log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
    echo "fuzz: $t ok, $runs executions"
  else
    echo "fuzz: $t FAILED (log: $log, reproducer in $artifacts)"
    tail -n 40 "$log"
    status=1
  fi
done
exit $status
