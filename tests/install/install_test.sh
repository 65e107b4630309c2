#!/usr/bin/env bash
# Installs the built project into a temporary prefix, then configures, builds and runs a
# separate project that uses find_package(ssta).
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
