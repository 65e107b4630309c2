#!/usr/bin/env bash
# Installs the built project into a temporary prefix, then configures, builds and runs two
# separate projects that use find_package(ssta):
#  - consumer: the whole library (ssta::ssta);
#  - map_consumer: the map alone (COMPONENTS map, ssta::map), as a planner takes it. Its
#    configure runs with the heavy packages disabled (CMAKE_DISABLE_FIND_PACKAGE_<name>), so
#    that looking for any of them fails it, and its binary must load none of their libraries.
set -euo pipefail
build_dir=$1
source_dir=$2
work=$(mktemp -d)
# cmake --install writes install_manifest.txt into the build folder: keep a copy of one that
# was there before, and leave the folder as it was.
manifest="$build_dir/install_manifest.txt"
if [ -f "$manifest" ]; then cp -p "$manifest" "$work/manifest.before"; fi
restore() {
  if [ -f "$work/manifest.before" ]; then cp -p "$work/manifest.before" "$manifest"; else rm -f "$manifest"; fi
  rm -rf "$work"
}
trap restore EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null

cmake -S "$source_dir/tests/install/consumer" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/build" >/dev/null
"$work/build/consumer"

heavy_packages=(OpenCV PCL SstaPCL Ceres SstaRosbag catkin rosbag roscpp rosbag_storage)
disabled=()
for p in "${heavy_packages[@]}"; do disabled+=("-DCMAKE_DISABLE_FIND_PACKAGE_$p=TRUE"); done
if ! cmake -S "$source_dir/tests/install/map_consumer" -B "$work/map_build" -DCMAKE_PREFIX_PATH="$work/prefix" \
    "${disabled[@]}" > "$work/map_configure.log" 2>&1; then
  cat "$work/map_configure.log"
  echo "install_test: find_package(ssta COMPONENTS map) failed with ${heavy_packages[*]} disabled" >&2
  exit 1
fi
cmake --build "$work/map_build" >/dev/null
echo "ldd map_consumer:"
ldd "$work/map_build/map_consumer" | sed 's/^/  /'
if ldd "$work/map_build/map_consumer" | grep -E 'lib(opencv|pcl|ceres|rosbag|roscpp|rostime|console_bridge)'; then
  echo "install_test: the map-only consumer loads the libraries above, which the map must not need" >&2
  exit 1
fi
mkdir "$work/map_run"
"$work/map_build/map_consumer" "$work/map_run"
