#!/bin/bash
# The Slurm fleet scripts (scripts/slurm/) without a cluster: sbatch, squeue and ssta are fakes
# that record their arguments. Checks what needs no scheduler: blanks, quotes, backslashes and
# spaces in recording paths; settings that look like globs passed as they are; one list per
# submission, passed to the jobs by path; the refusal while this --out's jobs are pending; bag
# files and rosbag2 folders as recordings; and the merge job stopping its other merges when
# one fails.
#   fleet_scripts_test.sh SOURCE_DIR
# Writes only under TMPDIR.
set -euo pipefail
src=$(realpath "${1:?source dir}")
fail() { echo "FAIL: $*" >&2; exit 1; }

root=$(mktemp -d "${TMPDIR:-/tmp}/ssta_fleet_scripts.XXXXXX")
cleanup() {
  local status=$?
  [[ -f $root/sleeper.pid ]] && kill "$(cat "$root/sleeper.pid")" 2> /dev/null || true
  rm -rf "$root"
  exit $status
}
trap cleanup EXIT
cd "$root"

# --- Fakes. sbatch: its arguments, one per line, in sbatch.<n>; prints job id 100<n>. ---
mkdir bin
cat > bin/sbatch << 'FAKE'
#!/bin/bash
n=$(ls "$FAKE_DIR" | grep -c '^sbatch\.' || true)
printf '%s\n' "$@" > "$FAKE_DIR/sbatch.$n"
echo "100$n"
FAKE
cat > bin/squeue << 'FAKE'
#!/bin/bash
printf '%s\n' "$*" > "$FAKE_DIR/squeue.args"
[[ -f $FAKE_DIR/queue ]] && cat "$FAKE_DIR/queue"
exit 0
FAKE
# ssta: build-map writes the map; query reads it; merge-maps fails on m0.ot (after the other
# merges started) and sleeps on m2.ot, leaving its pid.
cat > bin/ssta << 'FAKE'
#!/bin/bash
printf '%s\n' "$@" > "$FAKE_DIR/ssta.$$"
args=("$@")
[[ ${args[0]} == --threads ]] && args=("${args[@]:2}")
case ${args[0]} in
  query) exit 0 ;;
  build-map)
    for ((i = 1; i < ${#args[@]}; i++)); do [[ ${args[i]} == --map ]] && echo "map" > "${args[i + 1]}"; done ;;
  merge-maps)
    for a in "${args[@]}"; do
      [[ $a == */m0.ot ]] && { sleep 1; exit 1; }
      [[ $a == */m2.ot ]] && { echo $$ > "$FAKE_DIR/sleeper.pid"; exec sleep 60; }
    done ;;
esac
exit 0
FAKE
chmod +x bin/*
export PATH=$root/bin:$PATH FAKE_DIR=$root

# --- Recordings whose paths have quotes, backslashes, inner and outer blanks. ---
recs=("$root/rec dirs/Bob's run" "$root/rec dirs/a  b" "$root/rec dirs/back\\slash")
for r in "${recs[@]}"; do mkdir -p "$r"; echo frame > "$r/f"; done
{
  echo "# recordings"
  printf '  %s \t\n' "${recs[0]}"
  printf '\t%s  # the second\n' "${recs[1]}"
  echo ""
  printf '%s\n' "${recs[2]}"
} > list.txt
touch -- "--nodelist=node0" "--world-frame" "site0"  # what the globs below would match
cat > fleet.conf << CONF
SSTA=$root/bin/ssta
BUILD_MAP_CONFIG="c[01].yaml"
BUILD_MAP_ARGS="--world-frame site[0-9]"
CPUS_PER_TASK=1
MEM_PER_TASK=1G
TIME_PER_TASK=00:10:00
MAX_PARALLEL_TASKS=0
MERGE_CPUS=4
MERGE_MEM=1G
MERGE_TIME=00:10:00
MERGE_FAN_IN=2
PARTITION=""
SBATCH_ARGS="--nodelist=node[01-04] --qos=low"
CONF
touch c0.yaml

log=$("$src/scripts/slurm/fleet-submit.sh" --conf fleet.conf --recordings list.txt --out "out dir") ||
  fail "fleet-submit.sh failed: $log"
out=$root/out\ dir
first=$(sed -n 's/^lists: //p' <<< "$log")
[[ -d $first && $first == "$out"/submissions/* ]] || fail "no lists folder reported: $log"
diff <(printf '%s\n' "${recs[@]}") "$first/recordings.txt" > /dev/null ||
  fail "recordings.txt is not the three paths as written: $(cat "$first/recordings.txt")"
diff "$first/recordings.txt" "$first/todo.txt" > task.log 2>&1 || fail "todo.txt differs from recordings.txt"
build_args=$(cat sbatch.0) merge_args=$(cat sbatch.1)
grep -qxF -- "--nodelist=node[01-04]" <<< "$build_args" || fail "SBATCH_ARGS globbed or lost: $build_args"
grep -qxF -- "--qos=low" <<< "$merge_args" || fail "SBATCH_ARGS not given to the merge job: $merge_args"
grep -qxF -- "--comment=ssta-fleet $out" <<< "$build_args" || fail "the array has no comment naming --out"
[[ $(tail -n 3 sbatch.0) == "$root/fleet.conf"$'\n'"$out"$'\n'"$first/todo.txt" ]] ||
  fail "build-map-task.sh is not given CONF OUT TODO: $(tail -n 3 sbatch.0)"
[[ $(tail -n 1 sbatch.1) == "$first/recordings.txt" ]] || fail "merge-task.sh is not given its recordings list"

# A second submission has lists of its own; the first's stay as they were.
printf '%s\n' "${recs[1]}" > one.txt
log=$("$src/scripts/slurm/fleet-submit.sh" --conf fleet.conf --recordings one.txt --out "out dir") ||
  fail "second submission failed: $log"
second=$(sed -n 's/^lists: //p' <<< "$log")
[[ $second != "$first" && -f $second/todo.txt ]] || fail "the second submission reused $first"
diff <(printf '%s\n' "${recs[@]}") "$first/todo.txt" > task.log 2>&1 || fail "the second submission changed $first/todo.txt"

# Refused while this --out's jobs are pending or running, naming them; others' jobs do not count.
printf '%s\n' "1000_[0-2] ssta-fleet $out" "1001 ssta-fleet $out" "999 ssta-fleet $root/other" "998 " > queue
if log=$("$src/scripts/slurm/fleet-submit.sh" --conf fleet.conf --recordings list.txt --out "out dir" 2>&1); then
  fail "submitted while jobs of the earlier submission are pending: $log"
fi
grep -q "still pending or running: 1000_\[0-2\] 1001$" <<< "$log" || fail "the refusal does not name the jobs: $log"
grep -q 999 <<< "$log" && fail "the refusal names another --out's job: $log"
[[ $(ls "$out/submissions" | wc -l) == 2 ]] || fail "a refused submission left lists"
rm queue

# build-map-task.sh: its line of its list; settings not globbed.
SLURM_ARRAY_TASK_ID=1 "$src/scripts/slurm/build-map-task.sh" "$root/fleet.conf" "$out" "$first/todo.txt" > task.log 2>&1 ||
  fail "build-map-task.sh failed: $(cat task.log)"
[[ -f "$out/maps/a  b.ot" && $(cut -f2 "$out/done/a  b.tsv") == "${recs[1]}" ]] || fail "task 1 did not build 'a  b'"
build_call=$(grep -l '^build-map$' ssta.*)
grep -qxF "c[01].yaml" "$build_call" || fail "BUILD_MAP_CONFIG globbed: $(cat "$build_call")"
grep -qxF "site[0-9]" "$build_call" || fail "BUILD_MAP_ARGS globbed: $(cat "$build_call")"

# Every recording build-map takes: ROS 1 .bag, .mcap and .db3 files, rosbag2 folders, each
# named after its file without the extension.
mkdir -p bags/ros2_run
printf 'bag1' > bags/run1.bag
printf 'mcap' > bags/run2.mcap
printf 'db3' > bags/run3.db3
echo "rosbag2_bagfile_information:" > bags/ros2_run/metadata.yaml
printf '%s\n' "$root/bags/run1.bag" "$root/bags/run2.mcap" "$root/bags/run3.db3" "$root/bags/ros2_run" > bags.txt
log=$("$src/scripts/slurm/fleet-submit.sh" --conf fleet.conf --recordings bags.txt --out bags_out 2>&1) ||
  fail "bag recordings refused: $log"
bag_lists=$(sed -n 's/^lists: //p' <<< "$log")
diff bags.txt "$bag_lists/todo.txt" > /dev/null || fail "todo.txt does not list the bags: $(cat "$bag_lists/todo.txt")"
grep -q "4 of 4 recordings" <<< "$log" || fail "not every bag is to be mapped: $log"
rm -f ssta.*
SLURM_ARRAY_TASK_ID=0 "$src/scripts/slurm/build-map-task.sh" "$root/fleet.conf" "$root/bags_out" "$bag_lists/todo.txt" \
  > task.log 2>&1 || fail "build-map-task.sh failed on a bag: $(cat task.log)"
[[ -f bags_out/maps/run1.ot ]] || fail "the map of run1.bag is not maps/run1.ot: $(ls bags_out/maps)"
IFS=$'\t' read -r name rec_path rec_sum _ _ < bags_out/done/run1.tsv
[[ $name == run1 && $rec_path == "$root/bags/run1.bag" ]] || fail "run1's record: $name $rec_path"
[[ $rec_sum == $(sha256sum bags/run1.bag | cut -d' ' -f1) ]] || fail "run1's record does not hold the bag's SHA-256"
grep -qxF "$root/bags/run1.bag" "$(grep -l '^build-map$' ssta.*)" || fail "build-map was not given the bag"
SLURM_ARRAY_TASK_ID=3 "$src/scripts/slurm/build-map-task.sh" "$root/fleet.conf" "$root/bags_out" "$bag_lists/todo.txt" \
  > task.log 2>&1 || fail "build-map-task.sh failed on a rosbag2 folder: $(cat task.log)"
[[ -f bags_out/maps/ros2_run.ot ]] || fail "the map of the rosbag2 folder is not maps/ros2_run.ot"
# What build-map does not take is refused, naming it; so are two recordings of one name.
echo "notes" > bags/notes.txt
printf '%s\n' "$root/bags/notes.txt" > bad.txt
if log=$("$src/scripts/slurm/fleet-submit.sh" --conf fleet.conf --recordings bad.txt --out bags_out 2>&1); then
  fail "a text file was taken as a recording"
fi
grep -qF "recording '$root/bags/notes.txt' is neither a folder nor a .bag, .mcap or .db3 file" <<< "$log" ||
  fail "the refusal of a text file: $log"
mkdir -p bags/run1
printf '%s\n' "$root/bags/run1.bag" "$root/bags/run1" > clash.txt
if log=$("$src/scripts/slurm/fleet-submit.sh" --conf fleet.conf --recordings clash.txt --out bags_out 2>&1); then
  fail "run1.bag and the folder run1 were both taken: their maps share a name"
fi
grep -qF "two recordings are named 'run1'" <<< "$log" || fail "the refusal of a name clash: $log"

# merge-task.sh: when a merge fails, the merges still running are stopped.
mkdir -p merge/maps merge/done
for q in 0 1 2 3; do
  echo "m$q" > "merge/maps/m$q.ot"
  printf 'm%s\t%s\t-\t%s\t%s\n' "$q" "/rec/m$q" "$root/merge/maps/m$q.ot" "$(sha256sum "merge/maps/m$q.ot" | cut -d' ' -f1)" > "merge/done/m$q.tsv"
  echo "/rec/m$q" >> merge/recordings.txt
done
if "$src/scripts/slurm/merge-task.sh" "$root/fleet.conf" "$root/merge" "$root/merge/recordings.txt" > merge.log 2>&1; then
  fail "merge-task.sh succeeded although a merge failed"
fi
[[ -f sleeper.pid ]] || fail "the second merge did not start"
for _ in $(seq 1 20); do kill -0 "$(cat sleeper.pid)" 2> /dev/null || break; sleep 0.1; done
kill -0 "$(cat sleeper.pid)" 2> /dev/null && fail "merge-task.sh exited and left a merge running"
echo PASS
