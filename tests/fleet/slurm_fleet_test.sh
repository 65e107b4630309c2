#!/bin/bash
# The Slurm fleet recipe (scripts/slurm/) for real: a one-node Slurm cluster (munged,
# slurmctld, slurmd from Debian's packages) started inside this test, four short rendered
# recordings of one drive mapped as a job array and merged by the dependent job, checked
# against the same recordings mapped one after the other (build-map --resume) and against
# the truth; then a re-submission that must rebuild only the maps that were removed or
# damaged, after a submission refused while a held merge job of the same --out is pending.
# Fails, naming the reason, when the cluster cannot start.
#   slurm_fleet_test.sh SSTA_BINARY SOURCE_DIR
# Writes only under TMPDIR; every daemon it starts is stopped on exit.
set -euo pipefail
ssta=$(realpath "${1:?ssta binary}")
src=$(realpath "${2:?source dir}")

fail() { echo "FAIL: $*" >&2; exit 1; }
for tool in munged mungekey slurmctld slurmd sbatch squeue sinfo scontrol; do
  command -v "$tool" > /dev/null || fail "$tool is not installed (scripts/install-deps.sh installs slurm-wlm, slurmctld, slurmd and munge)"
done

# munged's socket path must stay short (sockaddr_un holds 108 bytes).
root=$(mktemp -d "${TMPDIR:-/tmp}/ssta_slurm.XXXXXX")
chmod 755 "$root"  # munged wants the socket's folder reachable by all
daemons=()  # pids of the daemons this test started, stopped in reverse order

cleanup() {
  local status=$?
  if [[ -f $root/slurm.conf ]]; then
    # Jobs first, so that no slurmstepd outlives slurmd.
    SLURM_CONF=$root/slurm.conf scancel --quiet --user=root > /dev/null 2>&1 || true
    for _ in $(seq 1 30); do
      [[ -z $(SLURM_CONF=$root/slurm.conf squeue -h 2> /dev/null) ]] && break
      sleep 1
    done
  fi
  local i
  for ((i = ${#daemons[@]} - 1; i >= 0; i--)); do kill "${daemons[i]}" 2> /dev/null || true; done
  for ((i = ${#daemons[@]} - 1; i >= 0; i--)); do
    for _ in $(seq 1 50); do kill -0 "${daemons[i]}" 2> /dev/null || break; sleep 0.1; done
    kill -9 "${daemons[i]}" 2> /dev/null || true
  done
  if ((status != 0)); then
    for log in "$root"/*.log "$root"/fleet/logs/*.log; do
      [[ -f $log ]] && { echo "--- $log (last lines)"; tail -n 15 "$log"; }
    done
  fi
  rm -rf "$root"
  exit $status
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# --- The recordings: one drive rendered, cut into four recordings of six frames each. ---
echo "rendering the drive"
"$ssta" synth --scene forest --seed 1 --frames 24 --width 320 --height 240 --focal 210 --rate 5 \
  --max-label-range 12 --threads 2 --out "$root/drive" > /dev/null
for q in 0 1 2 3; do
  rec="$root/recordings/rec$q"
  mkdir -p "$root/recordings"
  cp -r "$root/drive" "$rec"
  for cam in cam0 cam1; do
    { head -n 1 "$root/drive/$cam/data.csv"; tail -n +2 "$root/drive/$cam/data.csv" | sed -n "$((6 * q + 1)),$((6 * q + 6))p"; } \
      > "$rec/$cam/data.csv"
  done
  rm -rf "$rec/gt"  # a recording has no truth; the drive's truth scores the maps
  echo "$rec" >> "$root/recordings.txt"
done

# --- A one-node cluster. ---
echo "starting munged, slurmctld and slurmd in $root"
mungekey --create --keyfile="$root/munge.key" || fail "mungekey cannot create a key"
munged --foreground --force --key-file="$root/munge.key" --socket="$root/munge.sock" \
  --pid-file="$root/munged.pid" --log-file="$root/munged.log" --seed-file="$root/munged.seed" \
  > "$root/munged.out.log" 2>&1 &
daemons+=($!)
for _ in $(seq 1 50); do [[ -S $root/munge.sock ]] && break; sleep 0.1; done
[[ -S $root/munge.sock ]] || fail "munged did not start (munged.log below)"

# Two free ports of our own: other builds and tests run on this machine.
free_port() {
  local port
  for _ in $(seq 1 100); do
    port=$((20000 + RANDOM % 30000))
    if ! ss -Htan "( sport = :$port or sport = :$((port + 1)) )" 2> /dev/null | grep -q .; then
      echo "$port"
      return
    fi
  done
  fail "no free port pair found"
}
host=$(hostname -s)
# Addresses given, not looked up: a container's short hostname need not resolve.
memory_mb=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2))
mkdir -p "$root/state" "$root/spool"
# Starts slurmctld and slurmd on a free port pair and waits until the node is idle: up to 120 s,
# as a busy 2-core machine can take. Returns 1 when a daemon exited because another process took
# its port between free_port and the bind (the daemon's log says so); fails otherwise.
start_cluster() {
  port=$(free_port)
  cat > "$root/slurm.conf" << CONF
ClusterName=sstafleet
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$root/munge.sock
CredType=cred/munge
StateSaveLocation=$root/state
SlurmdSpoolDir=$root/spool
SlurmctldPidFile=$root/slurmctld.pid
SlurmdPidFile=$root/slurmd.pid
SlurmctldLogFile=$root/slurmctld.log
SlurmdLogFile=$root/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory_mb State=UNKNOWN
PartitionName=fleet Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$root/slurm.conf
  slurmctld -D -i -f "$SLURM_CONF" > "$root/slurmctld.out.log" 2>&1 &
  local ctld=$!
  slurmd -D -f "$SLURM_CONF" -N "$host" > "$root/slurmd.out.log" 2>&1 &
  local slurmd_pid=$!
  daemons+=("$ctld" "$slurmd_pid")
  state=""
  for _ in $(seq 1 240); do
    state=$(sinfo -h -o %T 2> /dev/null || true)
    [[ $state == idle ]] && return 0
    for pid in "$ctld" "$slurmd_pid"; do
      kill -0 "$pid" 2> /dev/null && continue
      if cat "$root"/slurm*.log 2> /dev/null | grep -qi "address already in use"; then
        kill "$ctld" "$slurmd_pid" 2> /dev/null || true
        wait "$ctld" "$slurmd_pid" 2> /dev/null || true
        daemons=("${daemons[@]:0:${#daemons[@]}-2}")
        for log in "$root"/slurm*.log; do mv "$log" "${log%.log}.port$port.log"; done
        return 1
      fi
      fail "a Slurm daemon exited at start (pid $pid; its log is below)"
    done
    sleep 0.5
  done
  fail "the node did not become idle within 120 s (state '$state'; logs below)"
}
if ! start_cluster; then
  echo "port $port or $((port + 1)) was taken before the daemons bound it; once more with other ports"
  start_cluster || fail "the daemons could not bind their ports twice (logs below)"
fi

# --- The recipe. ---
cat > "$root/fleet.conf" << CONF
SSTA=$ssta
BUILD_MAP_CONFIG=""
BUILD_MAP_ARGS="--world-frame drive"
CPUS_PER_TASK=1
MEM_PER_TASK=1G
TIME_PER_TASK=00:10:00
MAX_PARALLEL_TASKS=0
MERGE_CPUS=2
MERGE_MEM=1G
MERGE_TIME=00:10:00
MERGE_FAN_IN=2
PARTITION=fleet
SBATCH_ARGS=""
CONF
echo "submitting"
"$src/scripts/slurm/fleet-submit.sh" --conf "$root/fleet.conf" --recordings "$root/recordings.txt" \
  --out "$root/fleet" --wait || fail "the fleet jobs failed"
merged="$root/fleet/merged.ot"
[[ -f $merged ]] || fail "no merged map"

# The manifest: four recordings, four maps and the merged map, each sum as the files are now.
manifest="$root/fleet/manifest.tsv"
[[ $(grep -c $'^recording\t' "$manifest") == 4 ]] || fail "manifest does not list 4 recordings"
[[ $(grep -c $'^map\t' "$manifest") == 4 ]] || fail "manifest does not list 4 maps"
while IFS=$'\t' read -r kind _ path sum; do
  [[ $kind == map || $kind == merged ]] || continue
  [[ $(sha256sum "$path" | cut -d' ' -f1) == "$sum" ]] || fail "manifest: $path checksum differs"
done < <(grep -v '^#' "$manifest")
grep -q '^#@ssta merged_from:' "$merged" || fail "merged map has no provenance"
[[ $(grep -ac '^#@ssta   - {file: ' "$merged") == 4 ]] || fail "merged map does not list its 4 source maps"

# --- The same recordings one after the other into one map, and both against the truth. ---
echo "mapping the recordings one after the other"
resume=()
for q in 0 1 2 3; do
  "$ssta" build-map --sequence "$root/recordings/rec$q" --map "$root/sequential.ot" --world-frame drive "${resume[@]}" -q
  resume=(--resume)
done
accuracy() {
  "$ssta" export --map "$1" --format grid --out "$root/grid_$2" > /dev/null
  "$ssta" eval grid --pred "$root/grid_$2" --gt "$root/drive" | awk '/^accuracy/ {print $2}'
}
acc_merged=$(accuracy "$merged" merged)
acc_sequential=$(accuracy "$root/sequential.ot" sequential)
echo "grid accuracy against the truth: merged $acc_merged, one after the other $acc_sequential"
awk -v m="$acc_merged" -v s="$acc_sequential" 'BEGIN { exit !(s > 0.75 && m > 0.75) }' ||
  fail "a map is not near the truth (merged $acc_merged, sequential $acc_sequential; measured 0.80 both)"
awk -v m="$acc_merged" -v s="$acc_sequential" 'BEGIN { d = m - s; exit !(d < 0.015 && d > -0.015) }' ||
  fail "merged $acc_merged is not within 1.5 points of sequential $acc_sequential"

# --- No second submission while this one's jobs are pending: a held merge job refuses it. ---
echo "submitting with the merge job held, then again"
sed 's/^SBATCH_ARGS=.*/SBATCH_ARGS="--hold"/' "$root/fleet.conf" > "$root/held.conf"
held_log=$("$src/scripts/slurm/fleet-submit.sh" --conf "$root/held.conf" --recordings "$root/recordings.txt" \
  --out "$root/fleet") || fail "the held submission failed: $held_log"
held_job=$(sed -n 's/^merge-maps: job \([0-9]*\) .*/\1/p' <<< "$held_log")
[[ -n $held_job ]] || fail "no merge job in: $held_log"
if refusal=$("$src/scripts/slurm/fleet-submit.sh" --conf "$root/fleet.conf" --recordings "$root/recordings.txt" \
  --out "$root/fleet" 2>&1); then
  fail "submitted while merge job $held_job is pending: $refusal"
fi
grep -q "still pending or running: $held_job\$" <<< "$refusal" || fail "the refusal does not name job $held_job: $refusal"
scancel "$held_job"
for _ in $(seq 1 60); do
  [[ -z $(squeue -h -j "$held_job" -t PENDING,RUNNING 2> /dev/null) ]] && break
  sleep 0.5
done

# --- Resume: one map removed, one damaged; only those two are built again. ---
echo "resubmitting with rec1's map damaged and rec2's removed"
merged_sum=$(sha256sum "$merged" | cut -d' ' -f1)
untouched_sum=$(sha256sum "$root/fleet/maps/rec0.ot" | cut -d' ' -f1)
printf 'x' >> "$root/fleet/maps/rec1.ot"
rm "$root/fleet/maps/rec2.ot"
submit_log=$("$src/scripts/slurm/fleet-submit.sh" --conf "$root/fleet.conf" --recordings "$root/recordings.txt" \
  --out "$root/fleet" --wait) || fail "the resubmitted fleet jobs failed: $submit_log"
echo "$submit_log"
grep -q "2 of 4 recordings (2 already mapped)" <<< "$submit_log" || fail "the resubmission did not rebuild exactly 2 maps"
todo=$(sed -n 's/^lists: //p' <<< "$submit_log")/todo.txt
[[ $(sed -n '1p;2p' "$todo" | xargs -n1 basename | tr '\n' ' ') == "rec1 rec2 " ]] ||
  fail "rebuilt $(cat "$todo"), expected rec1 and rec2"
[[ $(sha256sum "$root/fleet/maps/rec0.ot" | cut -d' ' -f1) == "$untouched_sum" ]] || fail "rec0's map was rebuilt"
# The builds and the merge are deterministic: the same merged map, byte for byte.
[[ $(sha256sum "$merged" | cut -d' ' -f1) == "$merged_sum" ]] || fail "the resumed merge differs from the first"
echo "PASS"
