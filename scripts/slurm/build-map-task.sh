#!/bin/bash
# One array task of fleet-submit.sh: `ssta build-map` of the recording on line
# SLURM_ARRAY_TASK_ID + 1 of TODO (its submission's list, which no later submission rewrites)
# (a folder or a bag file) into OUT/maps/<name>.ot, then the task's record
# OUT/done/<name>.tsv (name, recording, its checksum, map, its checksum) once the map reads
# back. A map an interrupted task left (checkpoints, or a stop on SIGTERM at the time limit)
# is continued with --resume.
#   build-map-task.sh CONF OUT TODO
set -euo pipefail
conf=${1:?conf}
out=${2:?out}
todo=${3:?todo list}
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
index=${SLURM_ARRAY_TASK_ID:?"not a Slurm array task"}
rec=$(sed -n "$((index + 1))p" "$todo")
[[ -n $rec ]] || { echo "$todo: no line $((index + 1))" >&2; exit 1; }
name=$(recording_name "$rec")
map="$out/maps/$name.ot"
rm -f "$out/done/$name.tsv"

# Both settings are words split at blanks, not globbed.
args=()
read -ra configs <<< "${BUILD_MAP_CONFIG:-}"
for c in "${configs[@]+"${configs[@]}"}"; do args+=(--config "$c"); done
read -ra extra <<< "${BUILD_MAP_ARGS:-}"
args+=("${extra[@]+"${extra[@]}"}")
if [[ -f $map ]]; then
  # A map that does not read (a crash while the first save was renamed cannot leave one, but
  # a full disk can) is built again from the start.
  if "$SSTA" query --map "$map" --at 0,0 > /dev/null 2>&1; then
    args+=(--resume)
  else
    echo "$map: does not read back; building it again" >&2
    rm -f "$map"
  fi
fi
echo "build-map $name on $(hostname) with $CPUS_PER_TASK threads: $rec -> $map"
"$SSTA" --threads "${SLURM_CPUS_PER_TASK:-$CPUS_PER_TASK}" build-map --sequence "$rec" --map "$map" "${args[@]+"${args[@]}"}" -q
"$SSTA" query --map "$map" --at 0,0 > /dev/null  # it reads back: checksum and structure

# The recording's checksum: a bag file's SHA-256; a folder's, SHA-256 over the sorted list of
# its files' SHA-256 sums.
if [[ -d $rec ]]; then
  rec_sum=$(cd "$rec" && find . -type f -print0 | LC_ALL=C sort -z | xargs -0 sha256sum | sha256sum | cut -d' ' -f1)
else
  rec_sum=$(sha256sum "$rec" | cut -d' ' -f1)
fi
map_sum=$(sha256sum "$map" | cut -d' ' -f1)
printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$rec" "$rec_sum" "$map" "$map_sum" > "$out/done/$name.tsv.tmp"
mv "$out/done/$name.tsv.tmp" "$out/done/$name.tsv"
echo "done: $map sha256 $map_sum"
