#!/usr/bin/env bash
# Bearing-only SLAM on the five robots of UTIAS MRCLAM dataset 6 (docs/results/mrclam.md): for each robot,
# import (sightings of the other robots kept as clutter, no barcode given to the filter), run
# omnislam-slam --replay with config/slam/mrclam.yaml (+ the known start pose written by the importer),
# evaluate raw and --align, and print one table.
#
#   scripts/run-mrclam.sh [--build DIR] [--data DIR] [--out DIR] [--seed N | --seeds "1 2 ... N"]
#                         [--robots "1 2 3 4 5"] [--config FILE] [--import-args "ARGS"] [--slam-args "ARGS"]
#                         [--localise-in-truth]
#
# --seeds runs the filter once per seed on each robot's (one) import and prints, instead of the
# per-run table, each robot's median, min and max over the seeds and how many runs meet the issue's
# three bars (aligned ATE <= 0.4 m, landmark mean <= 0.35 m, <= 5 spurious); each run's files are
# robotN.seedS.* in the output folder. The filter samples its paths, so one seed is one draw.
#
# Diagnosis only (the figures of the issue are without): --import-args passes more options to the
# importer (e.g. "--drop-robot-sightings", "--odometry-from-truth"), --slam-args to omnislam-slam
# (e.g. "--set filter.particles=300"), and --localise-in-truth localises in the true map (importer
# --truth-map-out, omnislam-slam --load-map --localise) instead of mapping.
# Defaults: build dir $OMNISLAM_BUILD_DIR or build; data ../shared/datasets/mrclam/MRCLAM_Dataset6;
# out /tmp/omnislam-mrclam; seed 1. Needs no network; a few seconds per robot and seed on one core.
# A bad option stops the script before anything runs, naming it (exit 2); a failing step stops it with
# the step's name and the end of its messages (exit 1), and no table is printed.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${OMNISLAM_BUILD_DIR:-$ROOT/build}"
DATA="${OMNISLAM_DATASETS:-$ROOT/../shared/datasets}/mrclam/MRCLAM_Dataset6"
OUT=/tmp/omnislam-mrclam
SEED=1
SEED_GIVEN=0
SEEDS=""
ROBOTS="1 2 3 4 5"
IMPORT_ARGS=""
SLAM_ARGS=""
LOCALISE=0
CONFIG="$ROOT/config/slam/mrclam.yaml"
source "$ROOT/scripts/lib/options.sh"
while [ $# -gt 0 ]; do
  case "$1" in
    --build) opt_need run-mrclam.sh "$@"; BUILD="$2"; shift 2 ;;
    --data) opt_need run-mrclam.sh "$@"; DATA="$2"; shift 2 ;;
    --out) opt_need run-mrclam.sh "$@"; OUT="$2"; shift 2 ;;
    --seed) opt_need run-mrclam.sh "$@"; SEED="$2"; SEED_GIVEN=1; shift 2 ;;
    --seeds) opt_need run-mrclam.sh "$@"; SEEDS="$2"; shift 2 ;;
    --robots) opt_need run-mrclam.sh "$@"; ROBOTS="$2"; shift 2 ;;
    --config) opt_need run-mrclam.sh "$@"; CONFIG="$2"; shift 2 ;;
    --import-args) opt_need run-mrclam.sh "$@"; IMPORT_ARGS="$2"; shift 2 ;;
    --slam-args) opt_need run-mrclam.sh "$@"; SLAM_ARGS="$2"; shift 2 ;;
    --localise-in-truth) LOCALISE=1; shift ;;
    -h|--help) opt_usage "$0"; exit 0 ;;
    *) echo "run-mrclam.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
BIN="$BUILD/bin"
MULTI=0
if [ -n "$SEEDS" ]; then
  [ "$SEED_GIVEN" = 0 ] || { echo "run-mrclam.sh: give --seed or --seeds, not both" >&2; exit 2; }
  opt_integers run-mrclam.sh --seeds "$SEEDS"
  MULTI=1
else
  # One seed: the single-run files (robotN.*) would be overwritten by a second one; --seeds is for lists.
  [[ "$SEED" =~ ^[0-9]+$ ]] || { echo "run-mrclam.sh: --seed takes one non-negative integer (several: --seeds), got '$SEED'" >&2; exit 2; }
  SEEDS="$SEED"
fi
[ -n "${ROBOTS// /}" ] || { echo "run-mrclam.sh: --robots needs at least one robot number (1-5 in dataset 6)" >&2; exit 2; }
for r in $ROBOTS; do
  [[ "$r" =~ ^[1-9][0-9]*$ ]] || { echo "run-mrclam.sh: --robots takes robot numbers (1-5 in dataset 6), got '$r'" >&2; exit 2; }
done
[ -f "$CONFIG" ] || { echo "run-mrclam.sh: --config: no such file '$CONFIG'" >&2; exit 2; }
for exe in omnislam-import-mrclam omnislam-slam omnislam-eval; do
  [ -x "$BIN/$exe" ] || { echo "run-mrclam.sh: $BIN/$exe not built" >&2; exit 1; }
done
[ -d "$DATA" ] || { echo "run-mrclam.sh: dataset not found at $DATA" >&2; exit 1; }
mkdir -p "$OUT"

# One JSON key of a one-line JSON object.
key() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" <<< "$1"; }
fmt() { printf "%.${2:-2}f" "$1"; }
# An association figure, or n/a when the scored log has no SLAM_ASSOCIATIONS.
assoc_cell() { if [ "$(key "$1" assoc_available)" = true ]; then fmt "$(key "$1" "$2")"; else echo n/a; fi; }

rows=()
for r in $ROBOTS; do
  log="$OUT/robot$r.lcm"; cfg="$OUT/robot$r.yaml"
  loc_import=(); loc_slam=()
  if [ "$LOCALISE" = 1 ]; then
    loc_import=(--truth-map-out "$OUT/truthmap.yaml"); loc_slam=(--load-map "$OUT/truthmap.yaml" --localise)
  fi
  run_step run-mrclam.sh "omnislam-import-mrclam, robot $r" "$OUT/robot$r.import.txt" \
    "$BIN/omnislam-import-mrclam" "$DATA" --robot "$r" --out "$log" --duplicate-times keep-last \
    --slam-config-template "$CONFIG" --slam-config-out "$cfg" "${loc_import[@]}" $IMPORT_ARGS
  for seed in $SEEDS; do
    # One seed: robotN.*, as before; several: robotN.seedS.*.
    run="$OUT/robot$r"; [ "$MULTI" = 1 ] && run="$OUT/robot$r.seed$seed"
    res="$run.slam.lcm"
    run_step run-mrclam.sh "omnislam-slam, robot $r, seed $seed" "$run.slam.txt" \
      "$BIN/omnislam-slam" --replay "$log" --out "$res" --config "$cfg" --seed "$seed" "${loc_slam[@]}" $SLAM_ARGS
    raw=$("$BIN/omnislam-eval" "$res" --planar --json --no-tum) \
      || { echo "run-mrclam.sh: omnislam-eval failed on $res" >&2; exit 1; }
    ali=$("$BIN/omnislam-eval" "$res" --planar --json --no-tum --align --plot "$run.aligned") \
      || { echo "run-mrclam.sh: omnislam-eval --align failed on $res" >&2; exit 1; }
    echo "$raw" > "$run.eval.json"; echo "$ali" > "$run.eval-aligned.json"
    [ "$MULTI" = 1 ] && continue
    rows+=("$(printf "| %d | %s | %s / %s | %s / %s | %s / %s | %s/%s | %s | %s / %s |" "$r" \
      "$(key "$raw" frames)" \
      "$(fmt "$(key "$raw" dr_ate_rmse_m)")" "$(fmt "$(key "$raw" dr_ate_rmse_aligned_m)")" \
      "$(fmt "$(key "$raw" ate_rmse_m)")" "$(fmt "$(key "$ali" ate_rmse_m)")" \
      "$(fmt "$(key "$ali" landmark_mean_err_m)")" "$(fmt "$(key "$ali" landmark_max_err_m)")" \
      "$(key "$ali" landmarks_matched)" "$(key "$ali" landmarks_truth)" "$(key "$ali" landmarks_spurious)" \
      "$(assoc_cell "$ali" assoc_precision)" "$(assoc_cell "$ali" assoc_recall)")")
  done
done
# The dataset's name in the headings: "dataset N" for MRCLAM_DatasetN, else the folder's name.
DATASET="$(basename "$DATA")"
[[ "$DATASET" =~ ^MRCLAM_Dataset([0-9]+)$ ]] && DATASET="dataset ${BASH_REMATCH[1]}"
OPTS="${IMPORT_ARGS:+, importer $IMPORT_ARGS}${SLAM_ARGS:+, slam $SLAM_ARGS}$( [ "$LOCALISE" = 1 ] && echo ", localised in the true map" || true)"
if [ "$MULTI" = 1 ]; then
  echo "MRCLAM $DATASET, config $(basename "$CONFIG"), seeds $SEEDS$OPTS (after --align; median [min, max] over the seeds)"
  python3 "$ROOT/scripts/mrclam_seed_table.py" "$OUT" --robots "$ROBOTS" --seeds "$SEEDS"
  echo "(logs, configs, JSON and plots in $OUT)"
  exit 0
fi
echo "MRCLAM $DATASET, config $(basename "$CONFIG"), seed $SEED$OPTS (ATE RMSE in m; landmarks and association after --align)"
echo "| robot | frames | DR ATE raw / aligned | SLAM ATE raw / aligned | landmark mean / max | matched | spurious | assoc precision / recall |"
echo "|---|---|---|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
echo "(logs, configs, JSON and plots in $OUT)"
