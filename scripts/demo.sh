#!/usr/bin/env bash
# The main job on a default that ships with the project: render a short synthetic yard sequence
# with exact ground truth, classify every frame, and score the result against the truth.
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

if [ -d "$seq/gt" ] || [ -d "$seq/mav0/gt" ]; then
  echo "== scoring against the ground truth"
  "$ssta" eval labels --pred "$out/classified" --gt "$seq" --json "$out/eval.json" --pictures "$out/compare"
fi

cat <<MSG

Done. Look at:
  $out/classified/overlay/   the left images tinted by class (green traversable, blue semi,
                             red non-traversable, dark unknown, untinted undecided)
  $out/classified/frames/    per-frame JSON: every segment's plane, slope, step, class, reason
  $out/classified/config.yaml  every setting used (--config it to repeat the run)
  $out/compare/              ground truth | prediction, side by side
  $out/eval.json             accuracy, per-class IoU, coverage, confusion matrix
MSG
