#!/usr/bin/env bash
# Regression guard of the SLAM's behaviour: replays the committed fixtures (tests/data/regression/,
# cut from real runs of the sports hall, the room and MRCLAM) with `omnislam-slam --replay` in every
# proposal x association combination their config allows, and compares the SHA-256 of each output
# log with tests/data/regression/digests.txt. Any change of any output bit fails it. Each log is
# digested twice (scripts/lcm-log-split.py, events renumbered): without SLAM_HEALTH (NAME: the
# outputs as they were before that channel existed, so its digests stay those recorded then) and
# SLAM_HEALTH alone (NAME.health).
#   bash scripts/check-replay-regression.sh [BUILD_DIR]            check (CTest runs this)
#   bash scripts/check-replay-regression.sh [BUILD_DIR] --update   rewrite digests.txt: only for a
#       change of behaviour that is intended, and said so in its commit message and docs/design/decisions.md
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
mode="${2:-check}"
case "$mode" in check | --update) ;; *) echo "check-replay-regression: unknown mode '$mode' (--update or none)" >&2; exit 2 ;; esac
slam="$build/bin/omnislam-slam"
[ -x "$slam" ] || { echo "check-replay-regression: no $slam (build first)" >&2; exit 2; }
data="$root/tests/data/regression"
digests="$data/digests.txt"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The hall and room fixtures were cut from live runs of config/launch/{sports_hall,room}_slam.yaml
# (scripts/make-regression-fixtures.sh); their replays pair frames with the waits those runs used.
hall_pairing="--set pairing.max_wait_s=15 --set pairing.odometry_buffer_s=15 --set pairing.max_pending_frames=1000"
room_pairing="--set pairing.max_wait_s=12 --set pairing.odometry_buffer_s=12 --set pairing.max_pending_frames=1000"

# name | fixture | config | extra arguments
cases=(
  "hall-fs2-hungarian|sports_hall.lcm|config/slam/sports_hall.yaml|--association hungarian"
  "hall-fs2-ml|sports_hall.lcm|config/slam/sports_hall.yaml|--association ml"
  "hall-fs1-hungarian|sports_hall.lcm|config/slam/sports_hall.yaml|--association hungarian --set filter.proposal=fastslam1 --set filter.association_predictive=false --set filter.weight_at_predicted_pose=false"
  "hall-fs1-ml|sports_hall.lcm|config/slam/sports_hall.yaml|--association ml --set filter.proposal=fastslam1 --set filter.association_predictive=false --set filter.weight_at_predicted_pose=false"
  "room-fs1-ml|room.lcm|config/slam/room.yaml|--association ml"
  "room-fs1-hungarian|room.lcm|config/slam/room.yaml|--association hungarian"
  "room-fs2-ml|room.lcm|config/slam/room.yaml|--association ml --set filter.proposal=fastslam2"
  "room-fs2-hungarian|room.lcm|config/slam/room.yaml|--association hungarian --set filter.proposal=fastslam2"
  "mrclam-fs1-hungarian|mrclam_robot1.lcm|config/slam/mrclam.yaml|--association hungarian"
  "mrclam-fs1-ml|mrclam_robot1.lcm|config/slam/mrclam.yaml|--association ml"
  "mrclam-fs2-hungarian|mrclam_robot1.lcm|config/slam/mrclam.yaml|--association hungarian --set filter.proposal=fastslam2"
  "mrclam-fs2-ml|mrclam_robot1.lcm|config/slam/mrclam.yaml|--association ml --set filter.proposal=fastslam2"
  # The options the combinations above leave at their defaults: the paper's weight (Alg. 4 at x_t,
  # the density) and predictive pairing.
  "hall-fs2-hungarian-weight-paper|sports_hall.lcm|config/slam/sports_hall.yaml|--association hungarian --set filter.weight_at_predicted_pose=false --set filter.weight_term=density"
  "mrclam-fs2-hungarian-predictive|mrclam_robot1.lcm|config/slam/mrclam.yaml|--association hungarian --set filter.proposal=fastslam2 --set filter.association_predictive=true"
)

fail=0
: > "$work/digests.txt"
for c in "${cases[@]}"; do
  IFS='|' read -r name fixture config extra <<< "$c"
  out="$work/$name.lcm"
  args=(--config "$root/$config" --seed 1 --replay "$data/$fixture" --out "$out" --no-progress)
  case "$name" in hall-*) extra+=" $hall_pairing" ;; room-*) extra+=" $room_pairing" ;; esac
  # shellcheck disable=SC2206  # extra holds flags without spaces in their values
  args+=($extra)
  if ! "$slam" "${args[@]}" > "$work/$name.stdout" 2> "$work/$name.stderr"; then
    echo "FAIL $name: omnislam-slam exited non-zero; its stderr:" >&2
    tail -5 "$work/$name.stderr" >&2
    fail=1
    continue
  fi
  if ! python3 "$root/scripts/lcm-log-split.py" "$out" SLAM_HEALTH "$work/$name.health.lcm" "$work/$name.rest.lcm"; then
    fail=1
    continue
  fi
  for part in "$name" "$name.health"; do
    case "$part" in *.health) file="$work/$name.health.lcm" ;; *) file="$work/$name.rest.lcm" ;; esac
    sum="$(sha256sum "$file" | cut -d' ' -f1)"
    echo "$part $sum" >> "$work/digests.txt"
    [ "$mode" = check ] || continue
    want="$(awk -v n="$part" '$1 == n { print $2 }' "$digests")"
    if [ -z "$want" ]; then
      echo "FAIL $part: no digest in $digests" >&2
      fail=1
    elif [ "$want" != "$sum" ]; then
      echo "FAIL $part: output differs from the recorded behaviour (sha256 $sum, expected $want)" >&2
      fail=1
    else
      echo "ok   $part"
    fi
  done
done
if [ "$mode" = --update ]; then
  { echo "# SHA-256 of omnislam-slam --replay outputs (scripts/check-replay-regression.sh --update)"; cat "$work/digests.txt"; } > "$digests"
  echo "check-replay-regression: wrote $(wc -l < "$work/digests.txt") digests to $digests"
  exit "$fail"
fi
[ "$fail" = 0 ] && echo "check-replay-regression: ${#cases[@]} replays identical to the recorded behaviour"
exit "$fail"
