#!/usr/bin/env bash
# Scores omnislam-smooth (research/smoothing.md) on the runs scripts/run-mrclam.sh left in its output
# folder (one seed: robotN.slam.lcm and robotN.yaml): per robot, the batch smoothing of the run with the
# filter's associations (slam) or with the barcodes (labels), evaluated like run-mrclam.sh (--planar,
# raw and --align), one table. How good could the same data be; research/mrclam-diagnosis.md.
#
#   research/mrclam/smooth-runs.sh --associations slam|labels [--build DIR] [--out DIR]
#                                  [--robots "1 2 3 4 5"] [--smooth-args "ARGS"]
#
# Defaults: build dir $OMNISLAM_BUILD_DIR or build-r (a build with -DOMNISLAM_BUILD_RESEARCH=ON);
# out /tmp/omnislam-mrclam (run-mrclam.sh's default). --smooth-args passes more options to
# omnislam-smooth (e.g. "--initial-from-odometry" or "--incremental"). For the oracle association in
# the filter instead, see research_mrclam_subject_as_colour (research/README.md).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="${OMNISLAM_BUILD_DIR:-$ROOT/build-r}"
OUT=/tmp/omnislam-mrclam
ROBOTS="1 2 3 4 5"
ASSOC=""
SMOOTH_ARGS=""
source "$ROOT/scripts/lib/options.sh"
while [ $# -gt 0 ]; do
  case "$1" in
    --build) opt_need smooth-runs.sh "$@"; BUILD="$2"; shift 2 ;;
    --out) opt_need smooth-runs.sh "$@"; OUT="$2"; shift 2 ;;
    --robots) opt_need smooth-runs.sh "$@"; ROBOTS="$2"; shift 2 ;;
    --associations) opt_need smooth-runs.sh "$@"; ASSOC="$2"; shift 2 ;;
    --smooth-args) opt_need smooth-runs.sh "$@"; SMOOTH_ARGS="$2"; shift 2 ;;
    -h|--help) opt_usage "$0"; exit 0 ;;
    *) echo "smooth-runs.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$ASSOC" in slam|labels) ;; *) echo "smooth-runs.sh: --associations takes slam or labels, got '$ASSOC'" >&2; exit 2 ;; esac
opt_integers smooth-runs.sh --robots "$ROBOTS"
BIN="$BUILD/bin"
for exe in omnislam-smooth omnislam-eval; do
  [ -x "$BIN/$exe" ] || { echo "smooth-runs.sh: $BIN/$exe not built (a research build)" >&2; exit 1; }
done
key() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" <<< "$1"; }
fmt() { printf "%.2f" "$1"; }
echo "MRCLAM runs in $OUT smoothed with the $ASSOC associations${SMOOTH_ARGS:+ $SMOOTH_ARGS} (ATE RMSE in m; landmarks after --align)"
echo "| robot | frames | ATE raw / aligned | landmark mean / max | matched | spurious |"
echo "|---|---|---|---|---|---|"
for r in $ROBOTS; do
  run="$OUT/robot$r"
  [ -f "$run.slam.lcm" ] && [ -f "$run.yaml" ] \
    || { echo "smooth-runs.sh: $run.slam.lcm or $run.yaml missing (run scripts/run-mrclam.sh --out $OUT first)" >&2; exit 1; }
  run_step smooth-runs.sh "omnislam-smooth, robot $r" "$run.smooth.txt" \
    "$BIN/omnislam-smooth" "$run.slam.lcm" --out "$run.smooth.lcm" --config "$run.yaml" --associations "$ASSOC" $SMOOTH_ARGS
  raw=$("$BIN/omnislam-eval" "$run.smooth.lcm" --planar --json --no-tum)
  ali=$("$BIN/omnislam-eval" "$run.smooth.lcm" --planar --json --no-tum --align --plot "$run.smooth.aligned")
  printf "| %d | %s | %s / %s | %s / %s | %s/%s | %s |\n" "$r" "$(key "$raw" frames)" \
    "$(fmt "$(key "$raw" ate_rmse_m)")" "$(fmt "$(key "$ali" ate_rmse_m)")" \
    "$(fmt "$(key "$ali" landmark_mean_err_m)")" "$(fmt "$(key "$ali" landmark_max_err_m)")" \
    "$(key "$ali" landmarks_matched)" "$(key "$ali" landmarks_truth)" "$(key "$ali" landmarks_spurious)"
done
