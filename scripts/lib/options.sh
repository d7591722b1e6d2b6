# Shared by the scripts under scripts/ (sourced, not run): option values and steps that fail loudly.
# Each function takes the calling script's name first, for its messages.
#
#   opt_usage FILE                  prints FILE's header comment (from line 2 to the first line that is
#                                   not a comment) without the leading "# ": the script's --help
#   opt_need NAME "$@"              inside the option loop, before reading "$2": stops (exit 2) with
#                                   "NAME: OPTION needs a value" when the option is the last argument
#   opt_integers NAME OPTION LIST   stops (exit 2) unless every word of LIST is a non-negative integer
#   run_step NAME WHAT ERR CMD...   runs CMD with its standard error in the file ERR; a failure stops
#                                   the script (exit 1) naming WHAT, with the last lines of ERR

opt_usage() {
  awk 'NR == 1 { next } !/^#/ { exit } { sub(/^# ?/, ""); print }' "$1"
}

opt_need() {
  local name="$1"; shift
  [ $# -ge 2 ] || { echo "$name: $1 needs a value (see --help)" >&2; exit 2; }
}

opt_integers() {
  local name="$1" opt="$2" w
  [ -n "${3// /}" ] || { echo "$name: $opt needs at least one number" >&2; exit 2; }
  for w in $3; do
    [[ "$w" =~ ^[0-9]+$ ]] || { echo "$name: $opt takes non-negative integers, got '$w'" >&2; exit 2; }
  done
}

run_step() {
  local name="$1" what="$2" err="$3" rc=0; shift 3
  "$@" 2> "$err" || rc=$?
  [ "$rc" = 0 ] && return 0
  echo "$name: $what failed (exit $rc); the end of its messages ($err):" >&2
  tail -n 5 "$err" >&2
  exit 1
}
