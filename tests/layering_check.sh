#!/usr/bin/env bash
# Fails when a module includes a header of a module after it in the data's direction
# (src/CMakeLists.txt, docs/architecture.md): the layering stays a fact, not a habit.
#   tests/layering_check.sh SOURCE_DIR
set -euo pipefail
cd "$1"
declare -A allowed=(
  [core]="core"
  [files]="core files"
  [mcap]="core mcap"
  [mapping]="core files mcap mapping"
  [io]="core files io"
  [bags]="core files io mcap bags"
  [sensors]="core files io sensors"
  [stereo]="core files io stereo"
  [geometry]="core geometry"
  [analysis]="core files io stereo analysis"
  [fusion]="core files io mcap stereo analysis mapping fusion"
  [pictures]="core files io mcap mapping pictures"
  [mount]="core files io stereo analysis mount"
  [calibration]="core files io stereo calibration"
  [pipeline]="core files io mcap sensors stereo geometry analysis mapping fusion pictures mount calibration pipeline"
)
status=0
for module in "${!allowed[@]}"; do
  for file in $(find "src/$module" "include/ssta/$module" -name '*.h' -o -name '*.cpp' 2>/dev/null); do
    while IFS= read -r used; do
      case " ${allowed[$module]} " in
        *" $used "*) ;;
        *) echo "$file: the $module module includes the $used module (allowed: ${allowed[$module]})"; status=1 ;;
      esac
    done < <(sed -n 's|^#include "\(ssta/\)\{0,1\}\([a-z_]*\)/.*|\2|p' "$file" | sort -u)
  done
done
[ $status -eq 0 ] && echo "layering: every module includes only the modules before it"
exit $status
