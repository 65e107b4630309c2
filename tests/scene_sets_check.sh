#!/usr/bin/env bash
# The scene sets of scripts/scene_sets.sh (docs/accuracy.md): tuning holds 12 scenes, wide 16,
# report 12; no scene is in two sets (a setting tuned on a scene must not be reported on it);
# the named scenes come first in each; an unknown set name is refused with status 2.
#   scene_sets_check.sh <source_dir>
set -euo pipefail
cd "$1"
. scripts/scene_sets.sh

declare -A owner
fail=0
check_set() {
  local name=$1 expected=$2 run
  parse_set_args 30 "$name"
  if [ "${#runs[@]}" -ne "$expected" ]; then
    echo "set $name holds ${#runs[@]} scenes, expected $expected" >&2
    fail=1
  fi
  if [ "${runs[*]:0:4}" != "yard:${runs[0]#*:} hills:${runs[0]#*:} dropoff:${runs[0]#*:} forest:${runs[0]#*:}" ]; then
    echo "set $name does not begin with the four named scenes: ${runs[*]:0:4}" >&2
    fail=1
  fi
  for run in "${runs[@]}"; do
    if [ -n "${owner[$run]:-}" ]; then
      echo "scene $run is in both $name and ${owner[$run]}" >&2
      fail=1
    fi
    owner[$run]=$name
  done
}
check_set tuning 12
check_set wide 16
check_set report 12

status=0
(parse_set_args 30 nosuchset) 2>/dev/null || status=$?
if [ "$status" -ne 2 ]; then
  echo "an unknown set exits with $status, expected 2" >&2
  fail=1
fi
exit "$fail"
