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
rc=0
"$build/bin/omnislam-launch" config/launch/sports_hall_slam.yaml --log-file "$log" "$@" || rc=$?
# Ctrl-C / SIGTERM: the launcher stops every process in order, closes the log and exits 128 +
# the signal; what was recorded up to then is still summarised and evaluated below.
case "$rc" in
  0) ;;
  130 | 143) echo "run-default: the run was interrupted; what it recorded until then follows" >&2 ;;
  *) exit "$rc" ;;
esac
if [ ! -s "$log" ]; then
  echo "run-default: nothing was recorded in $log" >&2
  exit $((rc == 0 ? 1 : rc))
fi
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
exit "$rc"
