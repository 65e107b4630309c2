#!/bin/bash
# Maps many recordings of one site on a Slurm cluster (docs/fleet.md): one array task per
# recording runs `ssta build-map` (build-map-task.sh), then one job, once every task
# succeeded, merges the maps in a tree of `ssta merge-maps` (merge-task.sh) and writes a
# manifest of inputs and outputs with their SHA-256 sums.
#
#   fleet-submit.sh --conf fleet.conf --recordings LIST --out DIR [--wait]
#
# LIST holds one recording folder per line (its folder name names its map, so names must be
# unique). DIR receives maps/<name>.ot, done/<name>.tsv (a task's record: recording and map
# checksums), logs/, merged.ot and manifest.tsv. Submitting again resumes: a recording whose
# map exists with its record, the map's checksum as recorded, is not built again; a map that
# an interrupted task left behind is continued (build-map --resume).
# --wait: return when the merge job has ended, with its exit status.
set -euo pipefail

usage() { echo "usage: $0 --conf FILE --recordings LIST --out DIR [--wait]" >&2; exit 2; }
conf="" list="" out="" wait_for_merge=0
while (($#)); do
  case "$1" in
    --conf) conf=${2:?}; shift 2 ;;
    --recordings) list=${2:?}; shift 2 ;;
    --out) out=${2:?}; shift 2 ;;
    --wait) wait_for_merge=1; shift ;;
    *) usage ;;
  esac
done
[[ -n $conf && -n $list && -n $out ]] || usage
[[ -f $conf ]] || { echo "$conf: no such config file" >&2; exit 1; }
[[ -f $list ]] || { echo "$list: no such recording list" >&2; exit 1; }
here=$(cd "$(dirname "$0")" && pwd)
conf=$(realpath "$conf")
# shellcheck source=fleet.conf
source "$conf"
mkdir -p "$out"
out=$(realpath "$out")
mkdir -p "$out/maps" "$out/done" "$out/logs"

# The recordings, as absolute paths; blank lines and '#' comments are skipped.
recordings=()
declare -A seen=()
while IFS= read -r line || [[ -n $line ]]; do
  line=${line%%#*}
  line=$(echo "$line" | xargs)  # trims blanks
  [[ -z $line ]] && continue
  [[ -d $line ]] || { echo "$list: recording '$line' is not a folder" >&2; exit 1; }
  rec=$(realpath "$line")
  name=$(basename "$rec")
  if [[ -n ${seen[$name]:-} ]]; then
    echo "$list: two recordings are named '$name' ($(basename "${seen[$name]}") and $rec): the map of each is named after its folder" >&2
    exit 1
  fi
  seen[$name]=$rec
  recordings+=("$rec")
done < "$list"
((${#recordings[@]} > 0)) || { echo "$list: lists no recording" >&2; exit 1; }
printf '%s\n' "${recordings[@]}" > "$out/recordings.txt"

# A map is done when its task's record exists and the map still has the recorded checksum.
map_done() {
  local name=$1 record="$out/done/$1.tsv" map="$out/maps/$1.ot"
  [[ -f $record && -f $map ]] || return 1
  [[ $(cut -f5 "$record") == $(sha256sum "$map" | cut -d' ' -f1) ]]
}
todo=()
for rec in "${recordings[@]}"; do
  map_done "$(basename "$rec")" || todo+=("$rec")
done
printf '%s\n' "${todo[@]+"${todo[@]}"}" | sed '/^$/d' > "$out/todo.txt"

common=()
[[ -n ${PARTITION:-} ]] && common+=(--partition "$PARTITION")
# shellcheck disable=SC2206  # SBATCH_ARGS is a list of words by design
[[ -n ${SBATCH_ARGS:-} ]] && common+=($SBATCH_ARGS)

dependency=()
if ((${#todo[@]} > 0)); then
  array="0-$((${#todo[@]} - 1))"
  ((${MAX_PARALLEL_TASKS:-0} > 0)) && array+="%$MAX_PARALLEL_TASKS"
  build_job=$(sbatch --parsable "${common[@]}" --job-name=ssta-build-map --array="$array" \
    --cpus-per-task="$CPUS_PER_TASK" --mem="$MEM_PER_TASK" --time="$TIME_PER_TASK" \
    --output="$out/logs/build-map_%A_%a.log" "$here/build-map-task.sh" "$conf" "$out")
  build_job=${build_job%%;*}
  dependency=(--dependency="afterok:$build_job" --kill-on-invalid-dep=yes)
  echo "build-map: job array $build_job, ${#todo[@]} of ${#recordings[@]} recordings ($((${#recordings[@]} - ${#todo[@]})) already mapped)"
else
  echo "build-map: all ${#recordings[@]} recordings already mapped"
fi

wait_args=()
((wait_for_merge)) && wait_args=(--wait)
merge_output="$out/logs/merge_%j.log"
if ((wait_for_merge)); then
  # sbatch --wait prints the job id only when the job ends: run it in the background.
  status=0
  sbatch --parsable "${common[@]}" "${dependency[@]}" "${wait_args[@]}" --job-name=ssta-merge-maps \
    --cpus-per-task="$MERGE_CPUS" --mem="$MERGE_MEM" --time="$MERGE_TIME" --output="$merge_output" \
    "$here/merge-task.sh" "$conf" "$out" > "$out/logs/merge-job.txt" || status=$?
  echo "merge-maps: job $(cut -d';' -f1 < "$out/logs/merge-job.txt") ended with status $status"
  exit $status
fi
merge_job=$(sbatch --parsable "${common[@]}" "${dependency[@]}" --job-name=ssta-merge-maps \
  --cpus-per-task="$MERGE_CPUS" --mem="$MERGE_MEM" --time="$MERGE_TIME" --output="$merge_output" \
  "$here/merge-task.sh" "$conf" "$out")
echo "merge-maps: job ${merge_job%%;*} -> $out/merged.ot, $out/manifest.tsv"
