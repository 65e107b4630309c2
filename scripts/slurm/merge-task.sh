#!/bin/bash
# The merge job of fleet-submit.sh: the map of every recording in RECORDINGS (its
# submission's list; each map with its task's record) merged into OUT/merged.ot by a tree of
# `ssta merge-maps`, MERGE_FAN_IN maps at a time and up to MERGE_CPUS merges at once, then
# OUT/manifest.tsv: every recording, map and the merged map with its SHA-256 sum.
#   merge-task.sh CONF OUT RECORDINGS
set -euo pipefail
conf=${1:?conf}
out=${2:?out}
recordings=${3:?recordings list}
# When one merge fails, set -e ends the job: the merges still running in the background go too.
stop_merges() {
  local pids
  pids=$(jobs -pr)
  [[ -n $pids ]] || return 0
  # shellcheck disable=SC2086  # a list of pids
  kill $pids 2> /dev/null || true
  wait 2> /dev/null || true
}
trap stop_merges EXIT
# A recording's name, which names its map: a folder's name; a bag file's name without its
# .bag, .mcap or .db3.
recording_name() {
  local base
  base=$(basename "$1")
  case $base in *.bag | *.mcap | *.db3) [[ -d $1 ]] || base=${base%.*} ;; esac
  printf '%s\n' "$base"
}
# shellcheck source=fleet.conf
source "$conf"
((MERGE_FAN_IN >= 2)) || { echo "$conf: MERGE_FAN_IN must be at least 2" >&2; exit 1; }

inputs=()
while IFS= read -r rec; do
  name=$(recording_name "$rec")
  record="$out/done/$name.tsv" map="$out/maps/$name.ot"
  [[ -f $record ]] || { echo "$rec: no map was built (no $record)" >&2; exit 1; }
  [[ $(cut -f5 "$record") == $(sha256sum "$map" | cut -d' ' -f1) ]] ||
    { echo "$map: changed since its task recorded it" >&2; exit 1; }
  inputs+=("$map")
done < "$recordings"

# Levels of merges of MERGE_FAN_IN maps until one merge takes the rest. The evidence adds the
# same in any grouping (docs/fleet.md: up to where the clamps are reached).
work="$out/merge-work"
rm -rf "$work"
mkdir -p "$work"
level=0
while ((${#inputs[@]} > MERGE_FAN_IN)); do
  outputs=() running=()
  for ((first = 0; first < ${#inputs[@]}; first += MERGE_FAN_IN)); do
    group=("${inputs[@]:first:MERGE_FAN_IN}")
    if ((${#group[@]} == 1)); then
      outputs+=("${group[0]}")
      continue
    fi
    target="$work/level${level}_$((first / MERGE_FAN_IN)).ot"
    outputs+=("$target")
    "$SSTA" merge-maps "${group[@]}" --out "$target" -q &
    running+=($!)
    if ((${#running[@]} >= MERGE_CPUS)); then
      wait "${running[0]}"
      running=("${running[@]:1}")
    fi
  done
  for pid in "${running[@]+"${running[@]}"}"; do wait "$pid"; done
  inputs=("${outputs[@]}")
  level=$((level + 1))
done
"$SSTA" merge-maps "${inputs[@]}" --out "$out/merged.ot"
rm -rf "$work"

manifest="$out/manifest.tsv"
{
  printf '# kind\tname\tpath\tsha256\n'
  while IFS= read -r rec; do
    IFS=$'\t' read -r name rec_path rec_sum map map_sum < "$out/done/$(recording_name "$rec").tsv"
    printf 'recording\t%s\t%s\t%s\n' "$name" "$rec_path" "$rec_sum"
    printf 'map\t%s\t%s\t%s\n' "$name" "$map" "$map_sum"
  done < "$recordings"
  printf 'merged\t-\t%s\t%s\n' "$out/merged.ot" "$(sha256sum "$out/merged.ot" | cut -d' ' -f1)"
} > "$manifest.tmp"
mv "$manifest.tmp" "$manifest"
echo "manifest: $manifest"
