#!/usr/bin/env bash
# Builds the map alone (-DSSTA_MAP_ONLY=ON) with its Python module, with the heavy packages
# disabled (CMAKE_DISABLE_FIND_PACKAGE_<name>: looking for any of them fails the configure), and
# runs the Python map tests against that module: `ssta.Map` must work when only the map
# component is built. The full build's command line makes the tests' maps.
#   tests/install/map_only_test.sh FULL_BUILD_DIR SOURCE_DIR
set -euo pipefail
full_build=$(cd "$1" && pwd)
source_dir=$(cd "$2" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python=$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$full_build/CMakeCache.txt")

heavy_packages=(OpenCV PCL SstaPCL Ceres SstaRosbag catkin rosbag roscpp rosbag_storage)
disabled=()
for p in "${heavy_packages[@]}"; do disabled+=("-DCMAKE_DISABLE_FIND_PACKAGE_$p=TRUE"); done
if ! cmake -S "$source_dir" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DSSTA_MAP_ONLY=ON -DSSTA_BUILD_PYTHON=ON \
    -DPython3_EXECUTABLE="$python" "${disabled[@]}" > "$work/configure.log" 2>&1; then
  cat "$work/configure.log"
  echo "map_only_test: the map-only configure failed with ${heavy_packages[*]} disabled" >&2
  exit 1
fi
if ! cmake --build "$work/build" -j "${JOBS:-2}" > "$work/build.log" 2>&1; then
  tail -50 "$work/build.log"
  echo "map_only_test: the map-only build failed" >&2
  exit 1
fi
if ldd "$work/build/python/ssta/"_ssta*.so | grep -E 'lib(opencv|pcl|ceres|rosbag|roscpp|rostime|console_bridge)'; then
  echo "map_only_test: the map-only Python module loads the libraries above" >&2
  exit 1
fi
export PYTHONPATH="$work/build/python" SSTA_BUILD_DIR="$full_build" PYTHONDONTWRITEBYTECODE=1
"$python" -c 'import ssta, sys; sys.exit(0 if ssta.MAP_ONLY else "map_only_test: imported a full module")'
"$python" -m pytest -q -p no:cacheprovider --basetemp="$work/pytest" "$source_dir/python/tests/test_map.py"
