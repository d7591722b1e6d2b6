#!/usr/bin/env bash
# Builds and runs the benchmarks under bench/ (not part of the test suite). Each program prints its
# figures beside the baseline it is compared with in the same run; JSON copies go to build/bench/.
# Usage: bash scripts/run-bench.sh [NAME_FILTER]   e.g.  bash scripts/run-bench.sh fastslam
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/prepare.sh"
build="${OMNISLAM_BUILD_DIR:-$root/build}"
mkdir -p "$build/bench"
for exe in "$build"/bin/bench_*; do
  name="$(basename "$exe")"
  [[ -z "${1:-}" || "$name" == *"$1"* ]] || continue
  echo "== $name"
  "$exe" --benchmark_out="$build/bench/$name.json" --benchmark_out_format=json
done
