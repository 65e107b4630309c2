#!/usr/bin/env bash
# No test may leave files outside its temporary directory. CTest runs this as the setup and the
# cleanup of the fixture every test requires (tests/CMakeLists.txt):
#   litter_check.sh start <build_dir> <source_dir>   stamps the time, empties <build_dir>/test-tmp
#   litter_check.sh check <build_dir> <source_dir>   fails listing every file created or changed
#                                                    since in the source tree, in the build tree
#                                                    (outside CTest's Testing/), or left in
#                                                    <build_dir>/test-tmp, the TMPDIR of the tests
# Files a developer edits in the source tree while the suite runs show up too: run it again.
set -euo pipefail
mode=$1
build_dir=$(cd "$2" && pwd)
source_dir=$(cd "$3" && pwd)
stamp="$build_dir/Testing/litter_check.stamp"
tmp="$build_dir/test-tmp"

case "$mode" in
  start)
    mkdir -p "$build_dir/Testing"
    rm -rf "$tmp"
    mkdir -p "$tmp"
    touch "$stamp"
    ;;
  check)
    [ -f "$stamp" ] || { echo "litter_check: no stamp; run the suite through ctest"; exit 1; }
    litter=$(
      {
        # Source tree: everything but build folders and git's own files.
        find "$source_dir" \( -path "$source_dir/.git" -o -path "$source_dir/build*" -o -path "$build_dir" \) -prune \
          -o -newer "$stamp" ! -type d -print
        # Build tree: everything but CTest's logs and the tests' TMPDIR (checked below).
        find "$build_dir" \( -path "$build_dir/Testing" -o -path "$tmp" \) -prune -o -newer "$stamp" ! -type d -print
        # The tests' TMPDIR must be empty again: every TempDir removed.
        find "$tmp" -mindepth 1 -maxdepth 1
      } | grep -v -x -F -e "$source_dir" -e "$build_dir" || true
    )
    if [ -n "$litter" ]; then
      echo "litter_check: tests left these files outside their temporary directories:"
      echo "$litter" | head -n 50
      exit 1
    fi
    echo "litter_check: no test left files behind"
    ;;
  *)
    echo "usage: litter_check.sh start|check BUILD_DIR SOURCE_DIR" >&2
    exit 2
    ;;
esac
