#!/bin/bash
# Maps many recordings of one site on a Slurm cluster (docs/fleet.md): one array task per
# recording runs `ssta build-map` (build-map-task.sh), then one job, once every task
# succeeded, merges the maps in a tree of `ssta merge-maps` (merge-task.sh) and writes a
# manifest of inputs and outputs with their SHA-256 sums.
#
#   fleet-submit.sh --conf fleet.conf --recordings LIST --out DIR [--wait]
#
# LIST holds one recording per line, anything `ssta build-map --sequence` takes: an ASL / EuRoC
# folder, a KITTI drive, a rosbag2 folder, or a ROS 1 .bag, an .mcap or a .db3 file. Its name
# (a folder's name, a file's name without its extension) names its map, so names must be
# unique; blanks around a line and '#' comments are ignored. DIR receives maps/<name>.ot,
# done/<name>.tsv (a task's record: recording and map checksums), logs/, merged.ot and
# manifest.tsv, and submissions/<time>-<id>/ with this submission's recordings.txt and
# todo.txt: the jobs read their lists there, so no later submission changes them. Submitting
# again resumes: a recording whose map exists with its record, the map's checksum as recorded,
# is not built again; a map that an interrupted task left behind is continued (build-map
# --resume). Refused while jobs of an earlier submission to DIR are pending or running (the
# jobs carry the comment "ssta-fleet DIR").
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
# A recording's name, which names its map: a folder's name; a bag file's name without its
# .bag, .mcap or .db3.
recording_name() {
  local base
  base=$(basename "$1")
  case $base in *.bag | *.mcap | *.db3) [[ -d $1 ]] || base=${base%.*} ;; esac
  printf '%s\n' "$base"
}
here=$(cd "$(dirname "$0")" && pwd)
conf=$(realpath "$conf")
# shellcheck source=fleet.conf
source "$conf"
mkdir -p "$out"
out=$(realpath "$out")
mkdir -p "$out/maps" "$out/done" "$out/logs" "$out/submissions"

# One submission at a time per DIR: tasks of two would build the same maps at once, and the
# merge job of the first would merge maps the second is rewriting.
comment="ssta-fleet $out"
active=$(squeue -h --states=PENDING,RUNNING,CONFIGURING,SUSPENDED,REQUEUED -o '%i %k') ||
  { echo "squeue failed: cannot tell whether jobs of an earlier submission to $out still run" >&2; exit 1; }
ids=()
while IFS= read -r job; do
  [[ ${job#* } == "$comment" ]] && ids+=("${job%% *}")
done <<< "$active"
if ((${#ids[@]} > 0)); then
  echo "$out: jobs of an earlier submission are still pending or running: ${ids[*]}" >&2
  echo "  wait until they end (squeue), or cancel them (scancel ${ids[*]}), then submit again" >&2
  exit 1
fi

# The recordings, as absolute paths; blank lines and '#' comments are skipped.
recordings=()
declare -A seen=()
while IFS= read -r line || [[ -n $line ]]; do
  line=${line%%#*}
  line=${line#"${line%%[![:space:]]*}"}  # leading blanks
  line=${line%"${line##*[![:space:]]}"}  # trailing blanks
  [[ -z $line ]] && continue
  if [[ ! -d $line ]]; then
    [[ -e $line ]] || { echo "$list: recording '$line' does not exist" >&2; exit 1; }
    case $line in
      *.bag | *.mcap | *.db3) [[ -f $line ]] || { echo "$list: recording '$line' is not a file" >&2; exit 1; } ;;
      *) echo "$list: recording '$line' is neither a folder nor a .bag, .mcap or .db3 file" >&2; exit 1 ;;
    esac
  fi
  rec=$(realpath "$line")
  name=$(recording_name "$rec")
  if [[ -n ${seen[$name]:-} ]]; then
    echo "$list: two recordings are named '$name' (${seen[$name]} and $rec): the map of each is named after its recording" >&2
    exit 1
  fi
  seen[$name]=$rec
  recordings+=("$rec")
done < "$list"
((${#recordings[@]} > 0)) || { echo "$list: lists no recording" >&2; exit 1; }
# This submission's lists, under a name no other submission uses; the jobs get their paths.
submission=$(mktemp -d "$out/submissions/$(date +%Y%m%dT%H%M%S)-XXXXXX")
printf '%s\n' "${recordings[@]}" > "$submission/recordings.txt"

# A map is done when its task's record exists and the map still has the recorded checksum.
map_done() {
  local name=$1 record="$out/done/$1.tsv" map="$out/maps/$1.ot"
  [[ -f $record && -f $map ]] || return 1
  [[ $(cut -f5 "$record") == $(sha256sum "$map" | cut -d' ' -f1) ]]
}
todo=()
for rec in "${recordings[@]}"; do
  map_done "$(recording_name "$rec")" || todo+=("$rec")
done
printf '%s\n' "${todo[@]+"${todo[@]}"}" | sed '/^$/d' > "$submission/todo.txt"
echo "lists: $submission"

common=(--comment="$comment")
[[ -n ${PARTITION:-} ]] && common+=(--partition "$PARTITION")
# SBATCH_ARGS: words split at blanks, not globbed (--nodelist=node[01-04] stays as it is).
read -ra sbatch_args <<< "${SBATCH_ARGS:-}"
common+=("${sbatch_args[@]+"${sbatch_args[@]}"}")

dependency=()
if ((${#todo[@]} > 0)); then
  array="0-$((${#todo[@]} - 1))"
  ((${MAX_PARALLEL_TASKS:-0} > 0)) && array+="%$MAX_PARALLEL_TASKS"
  build_job=$(sbatch --parsable "${common[@]}" --job-name=ssta-build-map --array="$array" \
    --cpus-per-task="$CPUS_PER_TASK" --mem="$MEM_PER_TASK" --time="$TIME_PER_TASK" \
    --output="$out/logs/build-map_%A_%a.log" "$here/build-map-task.sh" "$conf" "$out" "$submission/todo.txt")
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
    "$here/merge-task.sh" "$conf" "$out" "$submission/recordings.txt" > "$out/logs/merge-job.txt" || status=$?
  echo "merge-maps: job $(cut -d';' -f1 < "$out/logs/merge-job.txt") ended with status $status"
  exit $status
fi
merge_job=$(sbatch --parsable "${common[@]}" "${dependency[@]}" --job-name=ssta-merge-maps \
  --cpus-per-task="$MERGE_CPUS" --mem="$MERGE_MEM" --time="$MERGE_TIME" --output="$merge_output" \
  "$here/merge-task.sh" "$conf" "$out" "$submission/recordings.txt")
echo "merge-maps: job ${merge_job%%;*} -> $out/merged.ot, $out/manifest.tsv"
