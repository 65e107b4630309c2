#!/usr/bin/env bash
# Accuracy of `ssta classify` on every synthetic scene with every stereo matcher (and with the
# true disparity, which measures the analysis alone), scored by `ssta eval labels`.
# Prints a Markdown table; per-run JSON goes to out/accuracy/.
#   scripts/accuracy.sh [FRAMES] [extra classify args...]
# Needs a built tree (build/apps/ssta): scripts/test.sh or scripts/demo.sh builds it.
set -euo pipefail
cd "$(dirname "$0")/.."
ssta=build/apps/ssta
frames=${1:-10}
shift || true
out=out/accuracy
mkdir -p "$out"

metric() {  # FILE -> "acc cov miou trav semi non"
  python3 - "$1" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))["metrics"]
f = lambda x: "n/a" if x is None else "%.3f" % x
i = m["iou"]
print(" | ".join([f(m["accuracy"]), f(m["coverage"]), f(m["mean_iou"]),
                  f(i["traversable"]), f(i["semi-traversable"]), f(i["non-traversable"])]))
PY
}

echo "| scene | stereo | accuracy | coverage | mean IoU | IoU trav. | IoU semi | IoU non-trav. |"
echo "|---|---|---|---|---|---|---|---|"
for scene in yard hills dropoff forest; do
  seq=$out/$scene
  [ -d "$seq" ] || "$ssta" synth --scene "$scene" --frames "$frames" --seed 1 --max-label-range 12 --out "$seq" >/dev/null
  for stereo in sgbm bm pcl_bb pcl_acso oracle; do
    args=()
    if [ "$stereo" = oracle ]; then
      args=(--oracle-disparity)
    else
      printf 'stereo:\n  algorithm: %s\n' "$stereo" > "$out/$stereo.yaml"
      args=(--config "$out/$stereo.yaml")
    fi
    rm -rf "$out/pred"
    "$ssta" classify --sequence "$seq" --out "$out/pred" -q "${args[@]}" "$@"
    "$ssta" eval labels --pred "$out/pred" --gt "$seq" --json "$out/${scene}_${stereo}.json" >/dev/null
    echo "| $scene | $stereo | $(metric "$out/${scene}_${stereo}.json") |"
  done
done
