#!/usr/bin/env bash
# Issue 45's oracles on generated worlds (research/README.md, docs/results/world-families.md "What an
# oracle reaches"): per seed, omnislam-gen-world's world and feature log as scripts/evaluate-worlds.sh
# makes them, the same world with exact inputs, and these runs of the shipped filter's step
# (research_oracle_worlds, config/slam/sports_hall.yaml, the same per-world settings, Hungarian),
# each scored by omnislam-eval into OUT/VARIANT/eval-hungarian-SEED.json:
#   filter             the shipped filter (the step recomposed from its stages; --check compares it
#                      with omnislam-slam itself, which must give the same JSON)
#   truth-assoc        each feature to the lamp its truth label names, clutter dropped
#   exact              exact odometry and bearings, no clutter, no window-wall misses; shipped filter
#   exact-truth-assoc  both
#   true-map           the lamps known at their true positions, localisation only, truth association
#   truth-birth        truth association, and each landmark born (when the filter's initialisation
#                      accepts its candidate) at its lamp's true position; exact-truth-birth: exact inputs
# then research/oracle_table.py prints the table (issue 45's criteria, scripts/worlds_table.py's code).
#
#   research/oracle-worlds.sh --family halls|irregular|corridors [--worlds 30] [--first-seed 1]
#                             [--rate-hz 1] [--jobs 2] [--out DIR] [--variants "filter truth-assoc ..."]
#                             [--check] [--set KEY=VALUE ...]
# --set goes to every run after the per-world settings (use a fresh --out for each setting).
# Needs omnislam-gen-world, omnislam-slam, omnislam-eval and research_oracle_worlds in
# ${OMNISLAM_BUILD_DIR:-build}/bin (a build with -DOMNISLAM_BUILD_RESEARCH=ON).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FAMILY=""; WORLDS=30; FIRST=1; RATE=1; JOBS=2; OUT=""; CHECK=0
VARIANTS="filter truth-assoc exact exact-truth-assoc truth-birth exact-truth-birth true-map"
SETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --family) FAMILY="$2"; shift 2 ;;
    --worlds) WORLDS="$2"; shift 2 ;;
    --first-seed) FIRST="$2"; shift 2 ;;
    --rate-hz) RATE="$2"; shift 2 ;;
    --jobs) JOBS="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --variants) VARIANTS="$2"; shift 2 ;;
    --check) CHECK=1; shift ;;
    --set) SETS+=(--set "$2"); shift 2 ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "oracle-worlds: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
case "$FAMILY" in halls|irregular|corridors) ;; *) echo "oracle-worlds: --family halls|irregular|corridors" >&2; exit 2 ;; esac
BIN="${OMNISLAM_BUILD_DIR:-$ROOT/build}/bin"
for t in omnislam-gen-world omnislam-slam omnislam-eval research_oracle_worlds; do
  [ -x "$BIN/$t" ] || { echo "oracle-worlds: $BIN/$t missing (build with -DOMNISLAM_BUILD_RESEARCH=ON)" >&2; exit 2; }
done
[ -n "$OUT" ] || OUT="$(mktemp -d "/tmp/omnislam-oracle-$FAMILY.XXXXXX")"
mkdir -p "$OUT/worlds"
[ "$CHECK" = 1 ] && VARIANTS="$VARIANTS shipped shipped-exact"
export BIN OUT FAMILY RATE VARIANTS ROOT
export SETS_STR="${SETS[*]+${SETS[*]}}"

# The world file with exact inputs: odometry without noise, no window-wall misses, no false blobs
# (the detector's base miss rate, 1/5136, has no switch in omnislam-gen-world).
exact_world() {
  python3 - "$1" "$2" <<'PY'
import re, sys
t = open(sys.argv[1]).read()
for k in ("distance_sigma_m_per_sqrt_m", "rotation_sigma_rad_per_sqrt_rad", "heading_sigma_rad_per_sqrt_m",
          "scale_error_sigma", "heading_drift_sigma_rad_per_m"):
    t, n = re.subn(r"(\n  %s: )[^\n]*" % k, r"\g<1>0", t)
    assert n == 1, k
t, n1 = re.subn(r"window_wall: \{enabled: true", "window_wall: {enabled: false", t)
t, n2 = re.subn(r"false_blobs: \{per_frame: [^,]*,", "false_blobs: {per_frame: 0,", t)
assert n2 == 1
open(sys.argv[2], "w").write(t)
PY
}
export -f exact_world

# One variant of one world: its run, its score; a failure is kept in VARIANT/fail-SEED.txt.
run_variant() {
  local v="$1" s="$2" w="$OUT/worlds/world-$2" d="$OUT/$1" log info args
  mkdir -p "$d"
  [ -s "$d/eval-hungarian-$s.json" ] && return 0
  case "$v" in exact*|shipped-exact) log="$w-exact.lcm"; info="$w-exact.info.json" ;; *) log="$w.lcm"; info="$w.info.json" ;; esac
  cp "$info" "$d/world-$s.info.json"
  args=(--config "$ROOT/config/slam/sports_hall.yaml" --seed "$s")
  local kv
  for kv in $(python3 "$ROOT/scripts/world_settings.py" "$info"); do
    args+=(--set "$kv")
  done
  for kv in $SETS_STR; do [ "$kv" = --set ] || args+=(--set "$kv"); done
  local ok=0
  case "$v" in
    shipped|shipped-exact)
      "$BIN/omnislam-slam" --replay "$log" --association hungarian "${args[@]}" --out "$d/slam-$s.lcm" --no-progress 2> "$d/run-$s.txt" && ok=1 ;;
    *)
      local extra=(--association filter)
      case "$v" in
        *truth-assoc) extra=(--association truth) ;;
        *truth-birth) extra=(--association truth --birth truth) ;;
        true-map) extra=(--association truth --map truth) ;;
      esac
      "$BIN/research_oracle_worlds" --in "$log" --out "$d/slam-$s.lcm" "${args[@]}" "${extra[@]}" \
        --fit-json "$d/fit-$s.json" 2> "$d/run-$s.txt" && ok=1 ;;
  esac
  if [ "$ok" = 1 ] && "$BIN/omnislam-eval" --json --no-tum "$d/slam-$s.lcm" > "$d/eval-hungarian-$s.json.part" 2>> "$d/run-$s.txt"; then
    mv "$d/eval-hungarian-$s.json.part" "$d/eval-hungarian-$s.json"
  else
    tail -n 5 "$d/run-$s.txt" > "$d/fail-$s.txt"
  fi
  rm -f "$d/slam-$s.lcm" "$d/eval-hungarian-$s.json.part"
}
export -f run_variant

one_world() {
  local s="$1" w="$OUT/worlds/world-$1" v
  if [ ! -s "$w.info.json" ] || [ ! -s "$w.lcm" ]; then
    "$BIN/omnislam-gen-world" --family "$FAMILY" --seed "$s" --rate-hz "$RATE" --out-world "$w.yaml" \
      --out-log "$w.lcm" --out-info "$w.info.json" 2> "$w.gen.txt"
  fi
  if [ ! -s "$w-exact.lcm" ]; then
    exact_world "$w.yaml" "$w-exact.yaml"
    "$BIN/omnislam-gen-world" --world "$w-exact.yaml" --seed "$s" --pixel-sigma-px 1e-6 \
      --out-log "$w-exact.lcm" --out-info "$w-exact.info.json" 2> "$w-exact.gen.txt"
  fi
  for v in $VARIANTS; do run_variant "$v" "$s"; done
  echo "oracle-worlds: world $s done ($(date +%T))" >&2
}
export -f one_world

LAST=$((FIRST + WORLDS - 1))
echo "oracle-worlds: $WORLDS $FAMILY worlds (seeds $FIRST..$LAST) at $RATE Hz: $VARIANTS; $JOBS jobs; in $OUT" >&2
seq "$FIRST" "$LAST" | xargs -P "$JOBS" -I{} bash -c 'one_world "$@"' _ {} || echo "oracle-worlds: some world failed (see */fail-*.txt)" >&2
python3 "$ROOT/research/oracle_table.py" "$OUT" --family "$FAMILY" --seeds "$FIRST" "$LAST" --rate-hz "$RATE" --variants $VARIANTS
