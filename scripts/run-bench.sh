#!/usr/bin/env bash
# Builds and runs the benchmarks under bench/ (not part of the test suite; docs/results/benchmarks.md). Each
# program prints its figures beside the baseline it is compared with in the same run; JSON copies go
# to build/bench/.
#   bench_fastslam, bench_detectors  Google Benchmark programs
#   bench_replay    needs a features log: $OMNISLAM_BENCH_LOG, else build/bench/sports_hall_features.lcm,
#                   recorded first (sports_hall_features.yaml at 10x on a private bus) when absent
#   bench_latency   runs the live pipeline (sports_hall_slam.yaml) for 10 and 100 particles at 4x, then
#                   issue 55's live case: the sports hall rendered at 30 Hz, 640 x 480, in real time, 100
#                   particles, $OMNISLAM_BENCH_LIVE_S simulated s (default 120): latency, CPU per process,
#                   PASS / FAIL against the targets
#   bench_memory    resident memory per process over $OMNISLAM_BENCH_MEMORY_S simulated s (default 3600,
#                   the acceptance run: one hour of wall time) in a generated hall at 30 Hz, in real time,
#                   recorded (config/launch/generated_world_slam.yaml)
# Usage: bash scripts/run-bench.sh [NAME_FILTER]   e.g.  bash scripts/run-bench.sh fastslam
# Environment: OMNISLAM_BUILD_DIR (default build/); OMNISLAM_BENCH_NO_PREPARE=1 uses the build as it
# is (no install/build step); OMNISLAM_BENCH_LOG (see above); OMNISLAM_BENCH_ARGS extra arguments for
# every Google Benchmark program (e.g. --benchmark_min_time=0.05); OMNISLAM_BENCH_LIVE_S and
# OMNISLAM_BENCH_MEMORY_S (see above).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
[[ "${OMNISLAM_BENCH_NO_PREPARE:-0}" == 1 ]] || bash "$root/scripts/prepare.sh"
build="${OMNISLAM_BUILD_DIR:-$root/build}"
mkdir -p "$build/bench"
# A private bus for the recording: no other run on this machine hears it or talks into it.
private_url="udpm://239.255.76.67:$((20000 + ($$ * 7 + 4242) % 30000))?ttl=0&recv_buf_size=4194304"

features_log() {
  local log="${OMNISLAM_BENCH_LOG:-$build/bench/sports_hall_features.lcm}"
  if [[ ! -s "$log" ]]; then
    echo "-- recording $log (config/launch/sports_hall_features.yaml at 10x on $private_url)" >&2
    local tmp="$log.part"
    # Only a recording of the whole scenario becomes the cached log: the launcher exits non-zero
    # when a process failed and 128 + signal when it was interrupted (the .part is then removed).
    trap 'rm -f "'"$tmp"'"' EXIT
    "$build/bin/omnislam-launch" "$root/config/launch/sports_hall_features.yaml" --url "$private_url" \
      --set speedup=10 --log-file "$tmp" > "$build/bench/record-features.out" 2>&1 \
      || { tail -20 "$build/bench/record-features.out" >&2; rm -f "$tmp"; return 1; }
    mv "$tmp" "$log"
    trap - EXIT
  fi
  echo "$log"
}

for exe in "$build"/bin/bench_*; do
  name="$(basename "$exe")"
  [[ -z "${1:-}" || "$name" == *"$1"* ]] || continue
  echo "== $name"
  case "$name" in
    bench_replay)
      log="$(features_log)"
      "$exe" --log "$log" --json "$build/bench/$name.json"
      ;;
    bench_latency)
      "$exe" --bin-dir "$build/bin" --out-dir "$build/bench" --json "$build/bench/$name.json"
      echo "== $name: live at 30 Hz (issue 55)"
      "$exe" --bin-dir "$build/bin" --out-dir "$build/bench" --json "$build/bench/${name}_live30.json" \
        --particles 100 --speedup 1 --image-rate-hz 30 --duration "${OMNISLAM_BENCH_LIVE_S:-120}"
      ;;
    bench_memory)
      "$exe" --bin-dir "$build/bin" --out-dir "$build/bench" --json "$build/bench/$name.json" \
        --family halls --seed 1 --rate-hz 30 --speedup 1 --particles 100 --duration "${OMNISLAM_BENCH_MEMORY_S:-3600}"
      ;;
    *)
      # shellcheck disable=SC2086
      "$exe" --benchmark_out="$build/bench/$name.json" --benchmark_out_format=json ${OMNISLAM_BENCH_ARGS:-}
      ;;
  esac
done
