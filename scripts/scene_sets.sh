# The sets of rendered scenes of docs/accuracy.md (tune on one, report on the other; `wide`
# checks a setting chosen on the tuning set against sixteen more scenes that neither set holds)
# and the command line the scripts that run over them share. Sourced by scripts/accuracy.sh and
# scripts/mount_benchmark.sh.

# parse_set_args DEFAULT_FRAMES [SET [FRAMES]] [-- ARGS...]: sets set_name (default tuning),
# frames (DEFAULT_FRAMES unless given), the array args (what follows --; a relative path that
# names a file in $caller_dir, where the user stood, made absolute) and the array runs,
# the set's scene:seed pairs, the named scenes first. A set that is not tuning, wide or report
# is named in one line with the calling script's usage, and exits with 2.
parse_set_args() {
  local named_seed random_seeds scene seed
  frames=$1
  shift
  set_name=${1:-tuning}
  [ $# -gt 0 ] && shift
  if [ $# -gt 0 ] && [ "$1" != "--" ]; then
    frames=$1
    shift
  fi
  [ "${1:-}" = "--" ] && shift
  # The script runs from the repository's root: a relative path among the args that names a
  # file where the user stands (a --config beside them) is made absolute.
  args=()
  local arg
  for arg in "$@"; do
    if [ -n "${caller_dir:-}" ] && [ "${arg#/}" = "$arg" ] && [ "${arg#-}" = "$arg" ] && [ -e "$caller_dir/$arg" ]; then
      arg=$caller_dir/$arg
    fi
    args+=("$arg")
  done
  case "$set_name" in
    tuning) named_seed=1; random_seeds="1 2 3 4 5 6 7 8" ;;
    wide) named_seed=2; random_seeds="9 10 11 12 13 14 15 16 17 18 19 20" ;;
    report) named_seed=7; random_seeds="101 102 103 104 105 106 107 108" ;;
    *)
      echo "scripts/$(basename "$0"): no scene set '$set_name'" \
        "(usage: scripts/$(basename "$0") tuning|wide|report [FRAMES] [-- args])" >&2
      exit 2
      ;;
  esac
  runs=()
  for scene in yard hills dropoff forest; do runs+=("$scene:$named_seed"); done
  for seed in $random_seeds; do runs+=("random:$seed"); done
}
