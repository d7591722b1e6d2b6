#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs the default scenario end to end
# (simulated sports hall of paper 000: simulator, capture, odometry, ceiling-light features and
# SLAM processes on one LCM URL, recorded into logs/), then prints what the recording holds and
# how the SLAM estimate compares with the truth (plots next to the log).
# Extra arguments go to omnislam-launch, e.g. --set speedup=20 --set seed=3.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bash scripts/prepare.sh
build="${OMNISLAM_BUILD_DIR:-$root/build}"
log="$root/logs/sports_hall_slam-$(date +%Y%m%d-%H%M%S).lcm"
"$build/bin/omnislam-launch" config/launch/sports_hall_slam.yaml --log-file "$log" "$@"
echo
echo "== what the run produced =="
"$build/bin/omnislam-logstat" "$log"
echo
echo "== SLAM against the truth =="
"$build/bin/omnislam-eval" "$log" --plot "${log%.lcm}"
echo "Plots: ${log%.lcm}.map.png ${log%.lcm}.errors.png; trajectories for evo: $log.slam.tum $log.truth.tum (dead reckoning: $log.odometry.tum)"
echo
echo "Replay it:  lcm-logplayer --lcm-url='udpm://239.255.76.67:7667?ttl=0' $log"
echo "Watch it:   bash scripts/lcm-spy.sh   (in another terminal, while replaying)"
