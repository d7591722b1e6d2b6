#!/usr/bin/env bash
# How the replay regression fixtures (tests/data/regression/*.lcm) were made: ODOMETRY and
# OMNI_FEATURES cut from a live run of the sports hall (150 s at speedup 5), of the room (60 s at
# speedup 4) and from MRCLAM dataset 6, robot 1 (first 200 s). Kept for the record: the fixtures are
# committed and must not be remade unless the message contract changes (then: new fixtures, new
# digests, said in the commit). Needs a build and ../shared/datasets.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
out="$root/tests/data/regression"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$build/bin/omnislam-launch" "$root/config/launch/sports_hall_slam.yaml" --log-file "$tmp/hall.lcm" \
  --set duration=150 --set speedup=5 --set odometry_only_after_s=15
python3 "$root/scripts/lcm_log_filter.py" "$tmp/hall.lcm" "$out/sports_hall.lcm" --channels ODOMETRY,OMNI_FEATURES
"$build/bin/omnislam-launch" "$root/config/launch/room_slam.yaml" --log-file "$tmp/room.lcm" --set duration=60
python3 "$root/scripts/lcm_log_filter.py" "$tmp/room.lcm" "$out/room.lcm" --channels ODOMETRY,OMNI_FEATURES
"$build/bin/omnislam-import-mrclam" "$root/../shared/datasets/mrclam/MRCLAM_Dataset6" --robot 1 \
  --out "$tmp/mrclam.lcm" --duplicate-times keep-last
python3 "$root/scripts/lcm_log_filter.py" "$tmp/mrclam.lcm" "$out/mrclam_robot1.lcm" \
  --channels ODOMETRY,OMNI_FEATURES --seconds 200
