#!/usr/bin/env bash
# Reproduces paper 000's table I and figs. 7-8 on the simulated sports hall, end to end from the
# features process's output: for each seed, the simulator, capture, odometry and ceiling-light
# features processes run live and are recorded; the recording is then replayed through
# omnislam-slam twice (Hungarian and Maximum-Likelihood association, same filter seed, 10 particles
# as in the paper) and scored with omnislam-eval. Prints a Markdown table (docs/results/slam-results.md).
#
#   scripts/reproduce-table1.sh [--seeds "1 2 ... 10"] [--speedup 10] [--out DIR] [--particles 10]
#                               [--keep-recordings] [--set KEY=VALUE ...]
# --set is passed to omnislam-slam (e.g. --set filter.resample_ess_fraction=1.0: the paper's
# resampling at every step); recordings already in --out are reused.
# Needs a build (scripts/build.sh). Takes about 45 s per seed at --speedup 10 on 2 cores.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SEEDS="1 2 3 4 5 6 7 8 9 10"
SPEEDUP=10
PARTICLES=10
OUT=""
KEEP=0
SETS=()
source "$ROOT/scripts/lib/options.sh"
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) opt_need reproduce-table1 "$@"; SEEDS="$2"; shift 2 ;;
    --speedup) opt_need reproduce-table1 "$@"; SPEEDUP="$2"; shift 2 ;;
    --particles) opt_need reproduce-table1 "$@"; PARTICLES="$2"; shift 2 ;;
    --out) opt_need reproduce-table1 "$@"; OUT="$2"; shift 2 ;;
    --keep-recordings) KEEP=1; shift ;;
    --set) opt_need reproduce-table1 "$@"; SETS+=(--set "$2"); shift 2 ;;
    -h|--help) opt_usage "$0"; exit 0 ;;
    *) echo "reproduce-table1: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
opt_integers reproduce-table1 --seeds "$SEEDS"
opt_integers reproduce-table1 --particles "$PARTICLES"
source "$ROOT/scripts/lib/reproduce.sh"
reproduce_prepare reproduce-table1
SLAM_CFG="$ROOT/config/slam/sports_hall.yaml"

for s in $SEEDS; do
  rec="$OUT/features-seed$s.lcm"
  reproduce_record reproduce-table1 "$ROOT/config/launch/sports_hall_features.yaml" "$s" "$SPEEDUP" "$rec" \
    "the features pipeline"
  for assoc in hungarian ml; do
    res="$OUT/slam-$assoc-seed$s.lcm"
    run_step reproduce-table1 "omnislam-slam, $assoc, seed $s" "$OUT/slam-$assoc-seed$s.txt" \
      "$BIN/omnislam-slam" --config "$SLAM_CFG" --seed "$s" --particles "$PARTICLES" --association "$assoc" \
      ${SETS[@]+"${SETS[@]}"} --replay "$rec" --out "$res" --no-progress
    "$BIN/omnislam-eval" --json --tum-out "$OUT/slam-$assoc-seed$s" "$res" > "$OUT/eval-$assoc-seed$s.json"
  done
  [ "$KEEP" = 1 ] || rm -f "$rec"
done
python3 "$ROOT/scripts/table1.py" "$OUT" $SEEDS
echo "reproduce-table1: files in $OUT" >&2
