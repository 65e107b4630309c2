#!/bin/bash
# scripts/soak.sh's table and verdict (--analyse) on samples written here, and its refusal of
# bad options, without rendering or mapping anything: growth the nodes explain passes, growth
# one kilobyte past the bound fails with status 1 naming the frame, a flat map whose memory
# grows fails, and malformed or too few samples end with status 2.
#   soak_script_test.sh SOURCE_DIR
# Writes only under TMPDIR.
set -euo pipefail
src=$(realpath "${1:?source dir}")
soak=$src/scripts/soak.sh
fail() { echo "FAIL: $*" >&2; exit 1; }

root=$(mktemp -d "${TMPDIR:-/tmp}/ssta_soak_script.XXXXXX")
trap 'rm -rf "$root"' EXIT

# Runs soak.sh with the arguments; sets $out (stdout and stderr) and $status.
run() {
  status=0
  out=$("$soak" "$@" 2>&1) || status=$?
}
expect() {  # expect STATUS PATTERN WHAT
  [[ $status == "$1" ]] || fail "$3: status $status, expected $1; output:"$'\n'"$out"
  grep -qE -- "$2" <<< "$out" || fail "$3: no line matches '$2'; output:"$'\n'"$out"
}

# The bound: growth <= 160 B x nodes gained + 256 B x frames + 16 MB (the constants of soak.sh).
allowed_kb() { echo $(((160 * $1 + 256 * $2 + 16 * 1048576) / 1024)); }

# 1. Memory that follows the nodes at 100 B/node: within, rows tagged start / middle / end.
{
  echo "# frames rss_kb hwm_kb nodes"
  for k in 1 2 3 4 5; do
    nodes=$((100000 + 200000 * (k - 1)))
    rss=$((100000 + (nodes - 100000) * 100 / 1024))
    echo "$((1000 * k)) $rss $((rss + 500)) $nodes"
  done
} > "$root/ok.tsv"
run --analyse "$root/ok.tsv"
expect 0 '^verdict: OK: resident memory grew 76\.3 MB from frame 1000 to 5000 while the map went from 100000 to 900000 nodes \(100\.0 B/node gained' "nodes explain"
expect 0 '^start +1000 +97\.7 ' "start row"
expect 0 '^middle +3000 ' "middle row (the sample nearest halfway)"
expect 0 '^end +5000 +174\.0 +174\.4 +900000 ' "end row: frames, RSS, HWM, nodes"

# 2. At the bound exactly, then 1 KB past it at the middle sample: status 1 naming that frame.
nodes_gained=300000 frames_gained=2000
edge=$((50000 + $(allowed_kb $nodes_gained $frames_gained)))
printf '1000 50000 50000 100000\n3000 %d %d 400000\n5000 %d %d 400000\n' "$edge" "$edge" "$edge" "$edge" > "$root/edge.tsv"
run --analyse "$root/edge.tsv"
expect 0 '^verdict: OK' "growth at the bound"
printf '1000 50000 50000 100000\n3000 %d %d 400000\n5000 %d %d 400000\n' "$((edge + 1))" "$((edge + 1))" "$edge" "$edge" > "$root/past.tsv"
run --analyse "$root/past.tsv"
expect 1 '^verdict: FAIL: at frame 3000 resident memory grew' "1 KB past the bound"

# 3. A map that stops growing while memory climbs 40 MB (a leak of about 8 KB a frame).
printf '250 80000 80000 500000\n2500 100000 100000 500000\n5000 120960 120960 500000\n' > "$root/leak.tsv"
run --analyse "$root/leak.tsv"
expect 1 '^verdict: FAIL: at frame 5000 resident memory grew 40\.0 MB, 22\.8 MB more than the map explains' "a leak"

# 4. Samples that cannot be judged: status 2 with the reason.
printf '250 80000 80000 500000\n5000 80000 80000 500000\n' > "$root/two.tsv"
run --analyse "$root/two.tsv"
expect 2 '2 samples; at least 3 are needed' "two samples"
printf '250 80000 80000 500000\n2500 80000 eighty 500000\n' > "$root/bad.tsv"
run --analyse "$root/bad.tsv"
expect 2 "bad\.tsv:2: expected four whole numbers" "a malformed row"
run --analyse "$root/missing.tsv"
expect 2 "missing\.tsv: cannot read" "a missing file"

# 5. Bad options end with status 2 before any work.
run --frames 0
expect 2 "^soak\.sh: --frames: expected a positive whole number, got '0'" "--frames 0"
run --speed -1
expect 2 "^soak\.sh: --speed: expected a positive number" "--speed -1"
run --checkpoint-every x
expect 2 "^soak\.sh: --checkpoint-every: expected a positive whole number" "--checkpoint-every x"
run --frobnicate
expect 2 "unknown option '--frobnicate'" "an unknown option"
run --frames 10 --ssta "$root/no-such-ssta"
expect 2 "no-such-ssta: no ssta binary" "a missing binary"
echo "soak script: all checks passed"
