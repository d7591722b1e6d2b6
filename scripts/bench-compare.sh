#!/usr/bin/env bash
# Speed of the filter against another build (e.g. of the previous commit): runs bench_fastslam and
# bench_replay of both builds alternately (base, new, base, new, ...; load from other work hits both
# alike) on the filter-step benchmarks and the committed sports-hall fixture, and prints per
# benchmark the median CPU time of each build and the ratio new / base, then their geometric mean.
#   bash scripts/bench-compare.sh BASE_BUILD_DIR [NEW_BUILD_DIR (default build/)]   ROUNDS=3 by default
# Both builds need the targets bench_fastslam and bench_replay. A report, not a test (exit 0).
set -eu
root="$(cd "$(dirname "$0")/.." && pwd)"
[ $# -ge 1 ] || { echo "usage: bench-compare.sh BASE_BUILD_DIR [NEW_BUILD_DIR]" >&2; exit 2; }
base="$1/bin"; new="${2:-$root/build}/bin"
for d in "$base" "$new"; do
  for b in bench_fastslam bench_replay; do [ -x "$d/$b" ] || { echo "bench-compare: no $d/$b (build it)" >&2; exit 2; }; done
done
rounds=${ROUNDS:-3}; out="$(mktemp -d)"; trap 'rm -rf "$out"' EXIT
filter='^BM_FilterStep(FastSlam1)?/(cow|hungarian|ml)/M:(10|100)/'
for r in $(seq $rounds); do
  for b in base new; do
    dir=$base; [ $b = new ] && dir=$new
    "$dir/bench_fastslam" --benchmark_filter="$filter" --benchmark_format=json --benchmark_out="$out"/fs.$b.$r.json --benchmark_out_format=json > /dev/null 2>&1
    "$dir/bench_replay" --log "$root"/tests/data/regression/sports_hall.lcm --config "$root"/config/slam/sports_hall.yaml --reps 3 --json "$out"/br.$b.$r.json > /dev/null 2>&1
  done
done
python3 - "$out" "$rounds" <<'PY'
import json, statistics, sys, math
out, rounds = sys.argv[1], int(sys.argv[2])
def load(b):
    fs, br = {}, {}
    for r in range(1, rounds + 1):
        for x in json.load(open(f"{out}/fs.{b}.{r}.json"))["benchmarks"]:
            fs.setdefault(x["name"], []).append(x["cpu_time"])
        for x in json.load(open(f"{out}/br.{b}.{r}.json"))["configurations"]:
            br.setdefault("bench_replay " + x["name"], []).append(x["cpu_s"] * 1e3 / x["frames"])
    return fs, br
(fb, rb), (fn, rn) = load("base"), load("new")
logs = []
print(f"{'benchmark':55s} {'base':>10s} {'new':>10s} {'new/base':>8s}")
for base, new, unit in ((fb, fn, "ms"), (rb, rn, "ms/frame")):
    for k in base:
        a, b = statistics.median(base[k]), statistics.median(new[k])
        logs.append(math.log(b / a))
        print(f"{k:55s} {a:10.3f} {b:10.3f} {b / a:8.3f}  ({unit}, cpu, median of {rounds})")
print(f"geometric mean new/base over {len(logs)} benchmarks: {math.exp(sum(logs) / len(logs)):.3f}")
PY
