#!/usr/bin/env bash
# Fails when a module includes a header of a module after it in the data's direction
# (src/CMakeLists.txt, docs/architecture.md): the layering stays a fact, not a habit.
#   tests/layering_check.sh SOURCE_DIR
set -euo pipefail
cd "$1"
declare -A allowed=(
  [core]="core"
  [io]="core io"
  [mcap]="core mcap"
  [bags]="core io mcap bags"
  [sensors]="core io sensors"
  [stereo]="core io stereo"
  [geometry]="core geometry"
  [analysis]="core io stereo analysis"
  [mapping]="core io mcap stereo analysis mapping"
  [mount]="core io stereo analysis mount"
  [calibration]="core io stereo calibration"
  [pipeline]="core io sensors stereo geometry analysis mapping mount calibration pipeline"
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
