#!/usr/bin/env bash
# The main job on a default that ships with the project: render a short synthetic yard sequence
# with exact ground truth, classify every frame, build the map, export its grid, ask it what a
# planner would, and score labels and map against the truth.
#   scripts/demo.sh            # renders out/demo/yard first
#   scripts/demo.sh SEQ        # classify and (when SEQ has gt/) score your own ASL sequence
# Installs the Debian packages it needs first (as root or with sudo).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "${JOBS:-2}" --target ssta_cli
ssta=build/apps/ssta
out=out/demo

seq=${1:-}
if [ -z "$seq" ]; then
  seq=$out/yard
  echo "== rendering a synthetic yard sequence into $seq"
  "$ssta" synth --scene yard --frames 20 --seed 1 --out "$seq"
fi

echo "== classifying $seq"
"$ssta" classify --sequence "$seq" --out "$out/classified"

echo "== building the map $out/map.ot"
"$ssta" build-map --sequence "$seq" --map "$out/map.ot" --picture "$out/map.png"
"$ssta" export --map "$out/map.ot" --format grid --out "$out/grid"

echo "== asking the map: the cell 3 m ahead, and a 1.0 x 0.6 m robot there"
"$ssta" query --map "$out/map.ot" --at 3,0
"$ssta" query --map "$out/map.ot" --footprint 3,0,0,1.0,0.6

if [ -d "$seq/gt" ] || [ -d "$seq/mav0/gt" ]; then
  echo "== scoring against the ground truth"
  "$ssta" eval labels --pred "$out/classified" --gt "$seq" --json "$out/eval.json" --pictures "$out/compare"
  "$ssta" eval grid --pred "$out/grid" --gt "$seq" --json "$out/eval_map.json" --picture "$out/eval_map.png"
  # What a planner is told: a 1.0 x 0.6 m robot every 0.5 m, unsafe and falsely blocked.
  "$ssta" eval footprints --map "$out/map.ot" --gt "$seq" --as-exported --json "$out/eval_footprints.json"
fi

cat <<MSG

Done. Look at:
  $out/classified/overlay/   the left images tinted by class (green traversable, blue semi,
                             red non-traversable, dark unknown, untinted undecided)
  $out/classified/frames/    per-frame JSON: every segment's plane, slope, step, class, reason
  $out/classified/config.yaml  every setting used (--config it to repeat the run)
  $out/compare/              ground truth | prediction, side by side
  $out/eval.json             labels: accuracy, per-class IoU, coverage, confusion matrix
  $out/map.png               the map for people: classes over the relief, the path, legend, scale
  $out/map.ot                the map (ssta query / ssta export read it; maps/README.md)
  $out/grid.png              the map's top-down grid in class colours (grid.yaml for map_server)
  $out/eval_map.png          truth | map | errors; eval_map.json the map's scores
  $out/eval_footprints.json  what a planner is told: unsafe and falsely blocked robot footprints
MSG
