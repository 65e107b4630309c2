#!/usr/bin/env bash
# The stereo matcher on real road images: every matcher setting worth comparing, run by
# `ssta eval stereo` over KITTI Stereo 2012 pairs with LiDAR disparity truth, as a Markdown table.
#
#   scripts/stereo_benchmark.sh [DATA] [-- extra args for ssta eval stereo, e.g. --pairs 5]
#
# DATA holds left/, right/ and gt/ (PNGs of the same names; truth 16 bit, disparity * 256, 0 =
# none) and defaults to ../shared/data/kitti2012-stereo beside the repository. Its licence (CC
# BY-NC-SA) is non-commercial: read it from there, never copy it into the repository.
# Every setting is config/sensors/kitti.yaml (search range 96 px, block 7) plus the keys in its
# row. Columns: D1 over all truth pixels (bad: off by more than 3 px and 5 %, or no disparity),
# D1 over matched pixels, end-point error over matched pixels, density (share of truth pixels
# with a disparity), the depth edges (of the truth pixels within 4 px of a nearer truth by a bad
# error, the share given a nearer disparity, bad: fattened; of those within 4 px of a farther
# truth, the share given a farther one: eroded), and the median wall and CPU (both cores) time
# of the matcher per pair (images read untimed).
# Pixels of all pairs are pooled. JSON per setting in out/stereo_benchmark/ (OUT= changes it).
# SETTINGS="shipped realtime" runs those rows only. Needs a built tree (build/apps/ssta; SSTA=
# names another binary). docs/performance.md shows a run.
set -euo pipefail
cd "$(dirname "$0")/.."
ssta=${SSTA:-build/apps/ssta}
data=../shared/data/kitti2012-stereo
if [ $# -gt 0 ] && [ "$1" != "--" ]; then
  data=$1
  shift
fi
[ "${1:-}" = "--" ] && shift
for folder in left right gt; do
  if [ ! -d "$data/$folder" ]; then
    echo "stereo_benchmark: $data/$folder: folder not found (DATA needs left/, right/ and gt/)" >&2
    exit 2
  fi
done
out=${OUT:-out/stereo_benchmark}
mkdir -p "$out"

# name | keys over config/sensors/kitti.yaml ("a.b: v; c.d: w"; empty: the shipped defaults)
settings=(
  "shipped|"
  "bm|stereo.algorithm: bm"
  "pcl_bb|stereo.algorithm: pcl_bb"
  "pcl_acso|stereo.algorithm: pcl_acso"
  "pcl_acso_no_ratio|stereo.algorithm: pcl_acso; stereo.pcl_ratio_filter: 0"
  "sgbm_hh4|stereo.sgbm_mode: hh4"
  "block5|stereo.block_size: 5"
  "block9|stereo.block_size: 9"
  "sgbm_p8_16|stereo.sgbm_p2: 16"
  "sgbm_p16_64|stereo.sgbm_p1: 16; stereo.sgbm_p2: 64"
  "realtime|stereo.downscale: 2; stereo.subpixel_window_px: 7"
  "half_no_subpixel|stereo.downscale: 2"
  "half_p4_32|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.sgbm_p1: 4; stereo.sgbm_p2: 32"
  "half_p8_64|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.sgbm_p2: 64"
  "half_p16_64|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.sgbm_p1: 16; stereo.sgbm_p2: 64"
  "half_p16_128|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.sgbm_p1: 16; stereo.sgbm_p2: 128"
  "half_uniq5|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.uniqueness_ratio: 5"
  "half_uniq15|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.uniqueness_ratio: 15"
  "half_lr2|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.left_right_max_diff: 2"
  "half_hh4|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.sgbm_mode: hh4"
  "half_block9|stereo.downscale: 2; stereo.subpixel_window_px: 7; stereo.block_size: 9"
)
if [ -n "${SETTINGS:-}" ]; then
  wanted=" $SETTINGS "
  kept=()
  for s in "${settings[@]}"; do
    [[ "$wanted" == *" ${s%%|*} "* ]] && kept+=("$s")
  done
  settings=("${kept[@]}")
fi

# "stereo.a: 1; stereo.b: 2" as a YAML file with a stereo section.
write_overlay() {
  local keys=$1 file=$2 pair
  echo "stereo:" > "$file"
  IFS=';' read -r -a pairs <<< "$keys"
  for pair in "${pairs[@]}"; do
    pair=${pair# }
    echo "  ${pair#stereo.}" >> "$file"
  done
}

field() { sed -n "s/^ *\"$1\": \([^,]*\),\{0,1\}$/\1/p" "$2"; }

echo "| setting | keys over config/sensors/kitti.yaml | D1 all | D1 matched | EPE [px] | density | edges: fattened | edges: eroded | ms / pair | CPU ms / pair |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for s in "${settings[@]}"; do
  name=${s%%|*}
  keys=${s#*|}
  configs=(--config config/sensors/kitti.yaml)
  if [ -n "$keys" ]; then
    write_overlay "$keys" "$out/$name.yaml"
    configs+=(--config "$out/$name.yaml")
  fi
  echo "stereo_benchmark: $name" >&2
  "$ssta" eval stereo --data "$data" "${configs[@]}" --json "$out/$name.json" "$@" > "$out/$name.txt"
  json=$out/$name.json
  awk -v name="$name" -v keys="${keys:-(shipped defaults)}" \
      -v d1="$(field d1_all "$json")" -v d1m="$(field d1_matched "$json")" \
      -v epe="$(field epe_px "$json")" -v dens="$(field density "$json")" \
      -v fat="$(field fattened_share "$json")" -v ero="$(field eroded_share "$json")" \
      -v ms="$(field median_match_ms "$json")" -v cpu="$(field median_match_cpu_ms "$json")" \
      'BEGIN { printf "| %s | %s | %.1f %% | %.1f %% | %.2f | %.1f %% | %.1f %% | %.1f %% | %.0f | %.0f |\n",
               name, keys, 100 * d1, 100 * d1m, epe, 100 * dens, 100 * fat, 100 * ero, ms, cpu }'
done
