#!/usr/bin/env bash
# Issue 54's oracle for the back end (docs/results/world-families.md, "What the smoother reaches with
# the true association"): per seed, omnislam-gen-world's world and feature log, then
# research_oracle_worlds solving ONE keyframe graph over the whole run (every frame a keyframe, the
# product's omnislam_smoothing with the config's backend.*) with the TRUE association, from the
# filter's poses, and omnislam-eval of the filter's output for dead reckoning's RMSE. Then
# research/graph_oracle_table.py prints the pass rate on the criteria the graph can be scored on.
#
#   research/graph-oracle-worlds.sh --family halls|irregular|corridors [--worlds 100] [--first-seed 1]
#                                   [--out DIR] [--known-ceiling] [--set KEY=VALUE ...]
# --known-ceiling: backend.ceiling=known_height at the world's ceiling_min_m (flat ceilings only).
# Needs a research build (-DOMNISLAM_BUILD_RESEARCH=ON) in ${OMNISLAM_BUILD_DIR:-build}.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FAMILY=""; WORLDS=100; FIRST=1; OUT=""; KNOWN=0; SETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --family) FAMILY="$2"; shift 2 ;;
    --worlds) WORLDS="$2"; shift 2 ;;
    --first-seed) FIRST="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --known-ceiling) KNOWN=1; shift ;;
    --set) SETS+=(--set "$2"); shift 2 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "graph-oracle-worlds: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
case "$FAMILY" in halls|irregular|corridors) ;; *) echo "graph-oracle-worlds: --family halls|irregular|corridors" >&2; exit 2 ;; esac
BIN="${OMNISLAM_BUILD_DIR:-$ROOT/build}/bin"
for t in omnislam-gen-world omnislam-eval research_oracle_worlds; do
  [ -x "$BIN/$t" ] || { echo "graph-oracle-worlds: $BIN/$t missing (a research build)" >&2; exit 2; }
done
[ -n "$OUT" ] || OUT="$(mktemp -d "/tmp/omnislam-graph-oracle-$FAMILY.XXXXXX")"
mkdir -p "$OUT"
for s in $(seq "$FIRST" $((FIRST + WORLDS - 1))); do
  w="$OUT/world-$s"
  [ -s "$OUT/graph-$s.json" ] && continue
  "$BIN/omnislam-gen-world" --family "$FAMILY" --seed "$s" --rate-hz 1 --out-world "$w.yaml" --out-log "$w.lcm" \
    --out-info "$w.info.json" 2> "$w.gen.txt"
  args=(--config "$ROOT/config/slam/sports_hall.yaml" --seed "$s")
  known=()
  [ "$KNOWN" = 1 ] && known=(--known-ceiling)
  for kv in $(python3 "$ROOT/scripts/world_settings.py" "$w.info.json" ${known[@]+"${known[@]}"}); do
    args+=(--set "$kv")
  done
  if "$BIN/research_oracle_worlds" --in "$w.lcm" --out "$OUT/out-$s.lcm" "${args[@]}" ${SETS[@]+"${SETS[@]}"} \
       --association truth --graph-init filter --graph-json "$OUT/graph-$s.json.part" 2> "$OUT/run-$s.txt" &&
     "$BIN/omnislam-eval" --json --no-tum "$OUT/out-$s.lcm" > "$OUT/eval-$s.json" 2>> "$OUT/run-$s.txt"; then
    mv "$OUT/graph-$s.json.part" "$OUT/graph-$s.json"
  else
    echo "graph-oracle-worlds: world $s failed: $(tail -n 1 "$OUT/run-$s.txt")" >&2
  fi
  rm -f "$OUT/out-$s.lcm" "$w.lcm"
  echo "graph-oracle-worlds: world $s done ($(date +%T))" >&2
done
python3 "$ROOT/research/graph_oracle_table.py" "$OUT"
