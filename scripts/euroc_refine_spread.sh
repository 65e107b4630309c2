#!/usr/bin/env bash
# Window-to-window stability of the online mount refinement on the still EuRoC recording
# (EuRoC MAV V1_01_easy, first 4.7 s, 95 frames; the MAV stands on the floor): build-map
# --static --refine with disjoint windows of 10 frames (solve every 10 frames), the ground
# referenced to gravity (EuRoC's body frame is the IMU's, x up). Every solve's estimate is kept
# apart from the mount in use (max_sigma_ratio 0.01: nothing is applied, so each window is
# solved through sensor.yaml's mount). Two gravity references:
#   imu    the IMU attitude filter (config/sensors/euroc.yaml: gravity.source imu)
#   fixed  one up vector for all frames: the mean accelerometer over the 4.7 s in cam0
# Prints each window's pitch / roll correction and their std and max - min.
#   scripts/euroc_refine_spread.sh [SEQUENCE]   (default /work/shared/data/euroc-v1-01-micro)
# Needs a built tree (build/apps/ssta).
set -euo pipefail
cd "$(dirname "$0")/.."
ssta=build/apps/ssta
seq=${1:-/work/shared/data/euroc-v1-01-micro}
out=out/euroc_refine
mkdir -p "$out"
cat > "$out/windows.yaml" <<'YAML'
refinement:
  ground_reference: gravity
  window_frames: 10
  min_frames: 10
  solve_every_frames: 10
  max_sigma_ratio: 0.01
YAML
# Mean accelerometer direction over the recording (IMU frame = body frame), in cam0:
# up_camera = R_BS(cam0)^T * a / |a|.
cat > "$out/fixed.yaml" <<'YAML'
gravity:
  source: fixed
  up_camera: [0.03568, -0.92761, -0.37183]
YAML
for gravity in imu fixed; do
  extra=()
  [ "$gravity" = fixed ] && extra=(--config "$out/fixed.yaml")
  "$ssta" build-map --sequence "$seq" --static --refine -q --config config/sensors/euroc.yaml \
    --config "$out/windows.yaml" "${extra[@]}" --map "$out/$gravity.ot" --json "$out/$gravity.json"
  python3 - "$out/$gravity.json" "$gravity" <<'PY'
import json, statistics, sys
r = json.load(open(sys.argv[1]))["refinement"]
print("gravity %s: %d windows of 10 frames" % (sys.argv[2], len(r["history"])))
for h in r["history"]:
    print("  frames %2d-%2d  pitch %+.3f  roll %+.3f  (1-sigma %.3f / %.3f deg)" % (
        h["frame"] - 9, h["frame"], h["pitch_correction_deg"], h["roll_correction_deg"],
        h["pitch_sigma_deg"], h["roll_sigma_deg"]))
for key in ("pitch", "roll"):
    v = [h[key + "_correction_deg"] for h in r["history"]]
    print("  %-5s mean %+.3f  std %.3f  max-min %.3f deg" % (key, statistics.mean(v), statistics.pstdev(v), max(v) - min(v)))
PY
done
