#!/usr/bin/env bash
# Soak benchmark: a long rendered sequence through `ssta build-map`, with the process's resident
# memory and the map's node count at every checkpoint; fails when memory grows beyond what the
# map's nodes explain. docs/robustness.md ("Soak: memory over a long run") gives the figures.
#
#   scripts/soak.sh                      # 5000 frames, 320x240, 0.02 m/s (about 20 min on 2 cores)
#   scripts/soak.sh --speed 0.25         # a drive of 83 m: the map grows all along
#   scripts/soak.sh --frames 1000 --keep # keep the rendered sequence and the map
#   scripts/soak.sh --analyse SAMPLES    # only the table and the verdict of a samples file
#
# Options:
#   --frames N            frames to render and fuse (5000)
#   --width W --height H  image size [px] (320x240; the focal length scales with the width, so
#                         the field of view is synth's default 640x480 one)
#   --speed V             vehicle speed [m/s] (0.02: 6.7 m in 5000 frames, so nearly every
#                         frame sees ground the map holds and few nodes are added; the weave
#                         period scales so the heading swings as at synth's default 1 m/s)
#   --scene S --seed K    synth scene and seed (yard, 1)
#   --checkpoint-every K  frames between map saves, one sample each (250)
#   --workdir DIR         where the sequence and the map go (a new folder under $TMPDIR or /tmp)
#   --keep                keep the sequence, map and samples (default: the folder is removed)
#   --ssta PATH           the ssta binary ($SSTA, else build/apps/ssta)
#   --analyse FILE        read samples (frames rss_kb hwm_kb nodes, one row per line) and only
#                         print the table and the verdict
#
# The verdict: from the first sample (start) to each later one, resident memory may grow by at
# most NODE_BYTES per map node gained, FRAME_BYTES per frame fused and SLACK_MB (see the
# constants below). Exit status 0: within; 1: growth beyond; 2: the run could not be measured.
set -euo pipefail

# An OctoMap node of the map (TravNode, 64 bytes) takes an 80-byte malloc chunk, and an inner
# node an array of 8 child pointers, another 80-byte chunk: at most 160 bytes per node.
NODE_BYTES=160
# Per fused frame the map keeps its recording fingerprint (timestamp and image hash, 16 bytes)
# and a sensor path point (24 bytes); vectors grow by doubling, and a checkpoint writes them as
# YAML text (about 60 bytes a frame) from a string that is freed again: 256 bytes a frame.
FRAME_BYTES=256
# Buffers that grow to the largest frame seen so far (images, disparity, points, the fusion's
# scratch) and the allocator's per-thread arenas: a few MB at 320x240.
SLACK_MB=16

usage() { sed -n '2,28p' "$0" | sed 's/^# \{0,1\}//'; }
die() { echo "soak.sh: $*" >&2; exit 2; }

# Prints the table of a samples file and the verdict; returns 0 (within) or 1 (beyond).
analyse() {
  local samples=$1
  [[ -r $samples ]] || die "$samples: cannot read the samples"
  awk -v node_bytes="$NODE_BYTES" -v frame_bytes="$FRAME_BYTES" -v slack_mb="$SLACK_MB" '
    function mb(kb) { return kb / 1024.0 }
    NF == 0 || $1 ~ /^#/ { next }
    NF < 4 || $1 !~ /^[0-9]+$/ || $2 !~ /^[0-9]+$/ || $3 !~ /^[0-9]+$/ || $4 !~ /^[0-9]+$/ {
      printf "soak.sh: %s:%d: expected four whole numbers (frames rss_kb hwm_kb nodes), got: %s\n", FILENAME, FNR, $0 > "/dev/stderr"
      bad = 1; exit 2
    }
    { n++; f[n] = $1; rss[n] = $2; hwm[n] = $3; nodes[n] = $4 }
    END {
      if (bad) exit 2
      if (n < 3) { printf "soak.sh: %d samples; at least 3 are needed (start, middle, end): more frames or a smaller --checkpoint-every\n", n > "/dev/stderr"; exit 2 }
      mid = 1
      half = (f[1] + f[n]) / 2
      for (i = 1; i <= n; i++) if ((f[i] - half) ^ 2 < (f[mid] - half) ^ 2) mid = i
      printf "%-6s %7s %8s %8s %10s %8s %10s %10s %9s\n", "", "frames", "RSS MB", "HWM MB", "nodes", "B/node", "+RSS MB", "+nodes", "+B/node"
      worst = -1e30
      for (i = 1; i <= n; i++) {
        tag = (i == 1 ? "start" : (i == mid ? "middle" : (i == n ? "end" : "")))
        d_rss = (rss[i] - rss[1]) * 1024.0; d_nodes = nodes[i] - nodes[1]; d_frames = f[i] - f[1]
        per = (d_nodes > 0 ? sprintf("%9.1f", d_rss / d_nodes) : sprintf("%9s", "-"))
        printf "%-6s %7d %8.1f %8.1f %10d %8.1f %+10.1f %+10d %s\n", tag, f[i], mb(rss[i]), mb(hwm[i]), nodes[i],
               (nodes[i] > 0 ? rss[i] * 1024.0 / nodes[i] : 0), mb(rss[i] - rss[1]), d_nodes, per
        allowed = node_bytes * (d_nodes > 0 ? d_nodes : 0) + frame_bytes * d_frames + slack_mb * 1048576.0
        if (d_rss - allowed > worst) { worst = d_rss - allowed; worst_i = i; worst_allowed = allowed; worst_d = d_rss }
      }
      printf "bound: growth since start <= %d B x nodes gained + %d B x frames + %d MB\n", node_bytes, frame_bytes, slack_mb
      if (worst > 0) {
        printf "verdict: FAIL: at frame %d resident memory grew %.1f MB, %.1f MB more than the map explains (%.1f MB)\n",
               f[worst_i], worst_d / 1048576.0, worst / 1048576.0, worst_allowed / 1048576.0
        exit 1
      }
      d_nodes = nodes[n] - nodes[1]
      printf "verdict: OK: resident memory grew %.1f MB from frame %d to %d while the map went from %d to %d nodes (%s B/node gained; allowed %.1f MB)\n",
             (rss[n] - rss[1]) / 1024.0, f[1], f[n], nodes[1], nodes[n],
             (d_nodes > 0 ? sprintf("%.1f", (rss[n] - rss[1]) * 1024.0 / d_nodes) : "-"),
             (node_bytes * (d_nodes > 0 ? d_nodes : 0) + frame_bytes * (f[n] - f[1]) + slack_mb * 1048576.0) / 1048576.0
    }' "$samples"
}

frames=5000 width=320 height=240 speed=0.02 scene=yard seed=1 every=250 workdir="" keep=0
ssta=${SSTA:-}
while (($#)); do
  case $1 in
    --frames) frames=${2:?}; shift 2 ;;
    --width) width=${2:?}; shift 2 ;;
    --height) height=${2:?}; shift 2 ;;
    --speed) speed=${2:?}; shift 2 ;;
    --scene) scene=${2:?}; shift 2 ;;
    --seed) seed=${2:?}; shift 2 ;;
    --checkpoint-every) every=${2:?}; shift 2 ;;
    --workdir) workdir=${2:?}; shift 2 ;;
    --keep) keep=1; shift ;;
    --ssta) ssta=${2:?}; shift 2 ;;
    --analyse) analyse "${2:?}"; exit $? ;;
    -h | --help) usage; exit 0 ;;
    *) die "unknown option '$1' (--help lists them)" ;;
  esac
done
for v in frames width height every; do
  [[ ${!v} =~ ^[1-9][0-9]*$ ]] || die "--${v/every/checkpoint-every}: expected a positive whole number, got '${!v}'"
done
[[ $speed =~ ^[0-9]*\.?[0-9]+$ ]] && awk -v s="$speed" 'BEGIN { exit !(s > 0) }' ||
  die "--speed: expected a positive number of m/s, got '$speed'"

root=$(cd "$(dirname "$0")/.." && pwd)
ssta=${ssta:-$root/build/apps/ssta}
[[ -x $ssta ]] || die "$ssta: no ssta binary (build it, or give --ssta / SSTA)"

if [[ -z $workdir ]]; then
  workdir=$(mktemp -d "${TMPDIR:-/tmp}/ssta-soak.XXXXXX")
else
  mkdir -p "$workdir"
fi
pid=""
cleanup() {
  if [[ -n $pid ]] && kill -0 "$pid" 2> /dev/null; then kill "$pid" && wait "$pid" 2> /dev/null || true; fi
  if ((keep == 0)); then rm -rf "$workdir"; fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# About 95 KB a frame at 320x240 (two PNGs, the truth's labels and disparity): refuse a run the
# disk cannot hold, with a 1 GB margin.
need_mb=$((frames * width * height * 13 / 10 / 1048576 + 1024))
free_mb=$(df -Pm "$workdir" | awk 'NR == 2 { print $4 }')
((free_mb >= need_mb)) || die "$workdir: $free_mb MB free, the run needs about $need_mb MB"

# The heading swings as at synth's defaults (1 m/s, 8 s weave period): the period scales with 1/speed.
focal=$(awk -v w="$width" 'BEGIN { printf "%.6g", 420 * w / 640 }')
period=$(awk -v s="$speed" 'BEGIN { printf "%.6g", 8 / s }')
seq_dir=$workdir/seq map=$workdir/soak.ot samples=$workdir/samples.tsv
echo "soak: rendering $frames frames (${width}x$height, f $focal px, $scene seed $seed, $speed m/s) into $seq_dir"
t0=$SECONDS
"$ssta" synth --scene "$scene" --seed "$seed" --frames "$frames" --width "$width" --height "$height" \
  --focal "$focal" --speed "$speed" --weave-period "$period" --out "$seq_dir" > "$workdir/synth.log" 2>&1 ||
  { cat "$workdir/synth.log" >&2; die "ssta synth failed"; }
echo "soak: rendered in $((SECONDS - t0)) s, $(du -sm "$seq_dir" | cut -f1) MB on disk"

printf 'map:\n  checkpoint_every_frames: %d\n' "$every" > "$workdir/soak.yaml"
echo "soak: build-map, one sample per checkpoint (every $every frames)"
t0=$SECONDS
"$ssta" build-map --sequence "$seq_dir" --map "$map" --config "$workdir/soak.yaml" --json "$workdir/summary.json" \
  -q > "$workdir/build-map.log" 2>&1 &
pid=$!
printf '# frames rss_kb hwm_kb nodes   (one row per map checkpoint; %s)\n' "$seq_dir" > "$samples"
last_inode=""
# The map file is replaced (renamed over) at each checkpoint: a new inode is a new checkpoint.
# Memory is read at once, while build-map works on the frames after it (a frame or two on).
while kill -0 "$pid" 2> /dev/null; do
  inode=$(stat -c %i "$map" 2> /dev/null || true)
  if [[ -n $inode && $inode != "$last_inode" ]]; then
    rss="" hwm=""
    while read -r key value _; do
      case $key in VmRSS:) rss=$value ;; VmHWM:) hwm=$value ;; esac
    done 2> /dev/null < "/proc/$pid/status" || true
    # The header before the node stream: frames_inserted and OctoMap's node count ("size").
    header=$(awk '/^#@ssta frames_inserted: / { f = $3 } /^size / { s = $2 } /^data$/ { print f, s; exit }' "$map" 2> /dev/null || true)
    if [[ -n $rss && -n $hwm && $header =~ ^[0-9]+\ [0-9]+$ ]]; then
      read -r done_frames nodes <<< "$header"
      # A checkpoint that replaced the file between stat and awk is read once only.
      [[ $done_frames == "${last_frames:-}" ]] || echo "$done_frames $rss $hwm $nodes" >> "$samples"
      last_inode=$inode last_frames=$done_frames
    fi
  fi
  sleep 0.2
done
status=0
wait "$pid" || status=$?
if ((status != 0)); then
  cat "$workdir/build-map.log" >&2
  die "ssta build-map failed (status $status)"
fi
summary=$(tr -d '\n ' < "$workdir/summary.json")
used=$(sed -n 's/.*"frames_used":\([0-9]*\).*/\1/p' <<< "$summary")
final_nodes=$(sed -n 's/.*"map_nodes":\([0-9]*\).*/\1/p' <<< "$summary")
free_only=$(grep -o '"reason":' <<< "${summary#*\"quality_failed\":}" | wc -l || true)
skipped=$(grep -o '"reason":' <<< "$summary" | wc -l || true)
skipped=$((skipped - free_only))
echo "soak: build-map fused $used of $frames frames ($free_only without verdicts by the quality" \
  "check: free space only; $skipped skipped) in $((SECONDS - t0)) s; final map $final_nodes nodes"
echo
verdict=0
analyse "$samples" || verdict=$?
if ((keep)); then echo "soak: kept $workdir (seq/, soak.ot, samples.tsv, summary.json)"; fi
exit "$verdict"
