#!/usr/bin/env bash
# Paper 002 end to end on the simulated room: for each seed the simulator, capture (colour
# catadioptric images), odometry and vertical-line features processes run live and are recorded
# (config/launch/room.yaml); the recording is replayed through omnislam-slam with the paper's method
# (FastSLAM 1.0 + per-measurement ML, config/slam/room.yaml) and with ours (FastSLAM 2.0 +
# hierarchical Hungarian: the same file with two --set), and scored in 2D with omnislam-eval
# --planar. Prints a Markdown table (docs/results/room-scenario.md).
#
#   scripts/reproduce-room.sh [--seeds "1 ... 10"] [--speedup 5] [--out DIR] [--keep-recordings] [--set KEY=VALUE ...]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SEEDS="1 2 3 4 5 6 7 8 9 10"
SPEEDUP=5
OUT=""
KEEP=0
SETS=()
source "$ROOT/scripts/lib/options.sh"
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) opt_need reproduce-room "$@"; SEEDS="$2"; shift 2 ;;
    --speedup) opt_need reproduce-room "$@"; SPEEDUP="$2"; shift 2 ;;
    --out) opt_need reproduce-room "$@"; OUT="$2"; shift 2 ;;
    --keep-recordings) KEEP=1; shift ;;
    --set) opt_need reproduce-room "$@"; SETS+=(--set "$2"); shift 2 ;;
    -h|--help) opt_usage "$0"; exit 0 ;;
    *) echo "reproduce-room: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
opt_integers reproduce-room --seeds "$SEEDS"
source "$ROOT/scripts/lib/reproduce.sh"
reproduce_prepare reproduce-room
CFG="$ROOT/config/slam/room.yaml"
for s in $SEEDS; do
  rec="$OUT/room-seed$s.lcm"
  reproduce_record reproduce-room "$ROOT/config/launch/room.yaml" "$s" "$SPEEDUP" "$rec" "the room"
  for method in paper ours; do
    extra=()
    [ "$method" = ours ] && extra=(--set filter.proposal=fastslam2 --set filter.association=hungarian)
    res="$OUT/slam-$method-seed$s.lcm"
    run_step reproduce-room "omnislam-slam, $method, seed $s" "$OUT/slam-$method-seed$s.txt" \
      "$BIN/omnislam-slam" --config "$CFG" --seed "$s" "${extra[@]}" ${SETS[@]+"${SETS[@]}"} --replay "$rec" --out "$res" \
      --no-progress
    "$BIN/omnislam-eval" --planar --json --no-tum "$res" > "$OUT/eval-$method-seed$s.json"
    rm -f "$res"
  done
  [ "$KEEP" = 1 ] || rm -f "$rec"
done
python3 "$ROOT/scripts/room_table.py" "$OUT" $SEEDS
echo "reproduce-room: files in $OUT" >&2
