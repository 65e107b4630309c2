#!/usr/bin/env bash
# The `mcap` export read by an independent reader (read_mcap.js: Foxglove's @mcap/core and
# @foxglove/rosmsg2-serialization, installed into the build folder from package-lock.json at build
# time), compared with the map's grid, CSV and map file (check_export.py), for zstd and
# uncompressed chunks. A map of 2 small rendered frames; a few seconds.
#   mcap_reader_test.sh SSTA_BINARY SOURCE_DIR NODE_MODULES_PARENT
set -euo pipefail
ssta=$1
here=$2/tests/mcap_reader
modules=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

"$ssta" synth --scene yard --frames 2 --width 320 --height 240 --focal 210 --out seq > /dev/null
"$ssta" build-map --sequence seq --map map.ot > /dev/null
"$ssta" export --map map.ot --format grid --out grid > /dev/null
"$ssta" export --map map.ot --format csv --out voxels > /dev/null
"$ssta" export --map map.ot --format mcap --out map.mcap
"$ssta" export --map map.ot --format mcap --compression none --out plain

for f in map plain; do
  NODE_PATH="$modules/node_modules" node "$here/read_mcap.js" "$f.mcap" --dump-map "$f.bin" > "$f.json"
  python3 "$here/check_export.py" "$f.json" "$f.bin" grid.pgm grid.yaml voxels.csv map.ot
done
python3 - <<'PY'
import json
a, b = json.load(open("map.json")), json.load(open("plain.json"))
assert a["compression"] == ["zstd"] and b["compression"] == ["none"], (a["compression"], b["compression"])
for key in ("map", "traversability", "voxels", "sensor_path", "tf_static"):
    assert a[key] == b[key], key
assert a["bytes"] < b["bytes"], (a["bytes"], b["bytes"])
print("zstd and uncompressed files decode alike")
PY
cmp map.bin plain.bin
