#!/usr/bin/env bash
# Evaluates the SLAM on a family of generated worlds (docs/results/world-families.md): for each seed,
# omnislam-gen-world draws a world and writes its feature log (no rendering), omnislam-slam replays
# it with config/slam/sports_hall.yaml (start pose and perception range set from the world, filter
# seed = world seed), omnislam-eval scores it (JSON); then scripts/worlds_table.py prints the pass
# rate on issue 45's criteria and the median / p90 of every figure, Hungarian and ML side by side,
# and writes OUT/summary.json and OUT/table.md.
#
#   scripts/evaluate-worlds.sh --family halls|irregular|corridors [--worlds 20] [--first-seed 1]
#                              [--rate-hz 1] [--association hungarian|ml|both] [--jobs 2]
#                              [--out DIR] [--keep-logs] [--known-ceiling] [--set KEY=VALUE ...]
# --known-ceiling gives each run the world's ceiling height as a user would measure it
# (backend.ceiling=known_height, backend.ceiling_height_m from the world's info: one flat ceiling;
# a world whose lamps are at several heights fails with a message). It acts only with the back end
# on (--set backend.mode=keyframes).
# --set is passed to omnislam-slam after the per-world settings (for experiments; the baseline
# uses none; the table's header names them). Worlds already scored in --out are not run again,
# whatever settings scored them: use a fresh --out for each setting. Needs omnislam-gen-world,
# omnislam-slam and omnislam-eval (scripts/build.sh, or OMNISLAM_BUILD_DIR).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FAMILY=""
WORLDS=20
FIRST=1
RATE=1
ASSOC=both
JOBS=2
OUT=""
KEEP=0
KNOWN=0
SETS=()
source "$ROOT/scripts/lib/options.sh"
while [ $# -gt 0 ]; do
  case "$1" in
    --family) opt_need evaluate-worlds "$@"; FAMILY="$2"; shift 2 ;;
    --worlds) opt_need evaluate-worlds "$@"; WORLDS="$2"; shift 2 ;;
    --first-seed) opt_need evaluate-worlds "$@"; FIRST="$2"; shift 2 ;;
    --rate-hz) opt_need evaluate-worlds "$@"; RATE="$2"; shift 2 ;;
    --association) opt_need evaluate-worlds "$@"; ASSOC="$2"; shift 2 ;;
    --jobs) opt_need evaluate-worlds "$@"; JOBS="$2"; shift 2 ;;
    --out) opt_need evaluate-worlds "$@"; OUT="$2"; shift 2 ;;
    --keep-logs) KEEP=1; shift ;;
    --known-ceiling) KNOWN=1; shift ;;
    --set) opt_need evaluate-worlds "$@"; SETS+=(--set "$2"); shift 2 ;;
    -h|--help) opt_usage "$0"; exit 0 ;;
    *) echo "evaluate-worlds: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$FAMILY" in halls|irregular|corridors) ;; *) echo "evaluate-worlds: --family must be halls, irregular or corridors (got '$FAMILY')" >&2; exit 2 ;; esac
case "$ASSOC" in hungarian|ml) METHODS="$ASSOC" ;; both) METHODS="hungarian ml" ;;
  *) echo "evaluate-worlds: --association must be hungarian, ml or both (got '$ASSOC')" >&2; exit 2 ;; esac
opt_integers evaluate-worlds --worlds "$WORLDS"
opt_integers evaluate-worlds --first-seed "$FIRST"
opt_integers evaluate-worlds --jobs "$JOBS"
[ "$WORLDS" -ge 1 ] && [ "$JOBS" -ge 1 ] && [ "$FIRST" -ge 1 ] || { echo "evaluate-worlds: --worlds, --jobs and --first-seed must be >= 1" >&2; exit 2; }
[[ "$RATE" =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "evaluate-worlds: --rate-hz takes a positive number, got '$RATE'" >&2; exit 2; }
BIN="${OMNISLAM_BUILD_DIR:-$ROOT/build}/bin"
for t in omnislam-gen-world omnislam-slam omnislam-eval; do
  [ -x "$BIN/$t" ] || { echo "evaluate-worlds: $BIN/$t missing: run scripts/build.sh first" >&2; exit 2; }
done
[ -n "$OUT" ] || OUT="$(mktemp -d "/tmp/omnislam-worlds-$FAMILY.XXXXXX")"
mkdir -p "$OUT"
export BIN OUT FAMILY RATE METHODS KEEP KNOWN ROOT
export SETS_STR="${SETS[*]+${SETS[*]}}"

# One world: generate, replay with each method, score. Failures are recorded in OUT/fail-*.txt
# (the table counts them as failed runs) rather than stopping the sweep.
one_world() {
  local s="$1" w="$OUT/world-$1" m todo=0
  for m in $METHODS; do [ -s "$OUT/eval-$m-$s.json" ] || todo=1; done
  [ "$todo" = 1 ] || return 0  # scored by an earlier run into this --out
  if [ ! -s "$w.info.json" ] || [ ! -s "$w.lcm" ]; then
    "$BIN/omnislam-gen-world" --family "$FAMILY" --seed "$s" --rate-hz "$RATE" --out-world "$w.yaml" \
      --out-log "$w.lcm" --out-info "$w.info.json" 2> "$w.gen.txt" || { cp "$w.gen.txt" "$OUT/fail-gen-$s.txt"; return 0; }
  fi
  local sets known=()
  [ "$KNOWN" = 1 ] && known=(--known-ceiling)
  sets=$(python3 "$ROOT/scripts/world_settings.py" "$w.info.json" ${known[@]+"${known[@]}"} 2> "$OUT/fail-settings-$s.txt") \
    || { cat "$OUT/fail-settings-$s.txt" >&2; [ "$KEEP" = 1 ] || rm -f "$w.lcm"; return 0; }
  rm -f "$OUT/fail-settings-$s.txt"
  local args=() kv
  for kv in $sets; do args+=(--set "$kv"); done
  for kv in $SETS_STR; do [ "$kv" = --set ] || args+=(--set "$kv"); done
  for m in $METHODS; do
    [ -s "$OUT/eval-$m-$s.json" ] && continue
    if "$BIN/omnislam-slam" --replay "$w.lcm" --config "$ROOT/config/slam/sports_hall.yaml" --seed "$s" \
         --association "$m" "${args[@]}" --out "$OUT/slam-$m-$s.lcm" --no-progress 2> "$OUT/slam-$m-$s.txt" &&
       "$BIN/omnislam-eval" --json --no-tum "$OUT/slam-$m-$s.lcm" > "$OUT/eval-$m-$s.json.part" 2> "$OUT/eval-$m-$s.txt"; then
      mv "$OUT/eval-$m-$s.json.part" "$OUT/eval-$m-$s.json"
    else
      cat "$OUT/slam-$m-$s.txt" "$OUT/eval-$m-$s.txt" 2> /dev/null | tail -n 5 > "$OUT/fail-$m-$s.txt"
    fi
    rm -f "$OUT/slam-$m-$s.lcm" "$OUT/eval-$m-$s.json.part"
  done
  [ "$KEEP" = 1 ] || rm -f "$w.lcm"
  echo "evaluate-worlds: world $s done ($(date +%T))" >&2
}
export -f one_world

LAST=$((FIRST + WORLDS - 1))
echo "evaluate-worlds: $WORLDS $FAMILY worlds (seeds $FIRST..$LAST) at $RATE Hz, $METHODS, $JOBS jobs, in $OUT" >&2
FRESH=0  # worlds with a method still to run: the ones the wall time is spent on
for s in $(seq "$FIRST" "$LAST"); do
  for m in $METHODS; do [ -s "$OUT/eval-$m-$s.json" ] || { FRESH=$((FRESH + 1)); break; }; done
done
T0=$(date +%s)
seq "$FIRST" "$LAST" | xargs -P "$JOBS" -I{} bash -c 'one_world "$@"' _ {}
T1=$(date +%s)
python3 "$ROOT/scripts/worlds_table.py" "$OUT" --family "$FAMILY" --seeds "$FIRST" "$LAST" --rate-hz "$RATE" \
  --methods $METHODS --wall-s $((T1 - T0)) --worlds-run "$FRESH" --jobs "$JOBS" \
  --extra-sets "$SETS_STR$([ "$KNOWN" = 1 ] && echo " --known-ceiling (backend.ceiling=known_height per world)")"
echo "evaluate-worlds: files in $OUT (summary.json, table.md)" >&2
