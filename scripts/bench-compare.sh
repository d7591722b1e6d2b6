#!/usr/bin/env bash
# Speed of the filter against another build (e.g. of the previous commit): runs bench_fastslam and
# bench_replay of both builds alternately (base, new, base, new, ...; load from other work hits both
# alike) on the filter-step benchmarks and the committed sports-hall fixture, and prints per
# benchmark the median CPU time of each build and the ratio new / base, then their geometric mean
# and range.
#   bash scripts/bench-compare.sh BASE_BUILD_DIR [NEW_BUILD_DIR (default build/)]
# Environment:
#   ROUNDS=3                 alternations (medians over them)
#   BASE_CONFIG, NEW_CONFIG  the SLAM config bench_replay of each build reads. Default: each build's
#                            own source tree's config/slam/sports_hall.yaml (the tree is read from
#                            the build's CMakeCache.txt), which an older build accepts. When the two
#                            files ask for different behaviour, give configs that ask for the same
#                            (the ratio of bench_replay compares like with like only then).
#   LOG                      the features log (default: tests/data/regression/sports_hall.lcm of this tree)
# Both builds need the targets bench_fastslam and bench_replay. A report, not a test (exit 0).
set -eu
root="$(cd "$(dirname "$0")/.." && pwd)"
[ $# -ge 1 ] || { echo "usage: bench-compare.sh BASE_BUILD_DIR [NEW_BUILD_DIR]" >&2; exit 2; }
base_build="$(cd "$1" && pwd)"; new_build="$(cd "${2:-$root/build}" && pwd)"
base="$base_build/bin"; new="$new_build/bin"
for d in "$base" "$new"; do
  for b in bench_fastslam bench_replay; do [ -x "$d/$b" ] || { echo "bench-compare: no $d/$b (build it)" >&2; exit 2; }; done
done
# The source tree a build was configured from (CMAKE_HOME_DIRECTORY in its cache).
source_of() {
  local s
  s="$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$1/CMakeCache.txt" 2> /dev/null || true)"
  [ -n "$s" ] && [ -d "$s" ] || { echo "bench-compare: cannot read the source tree of $1 from its CMakeCache.txt" >&2; exit 2; }
  echo "$s"
}
base_config="${BASE_CONFIG:-$(source_of "$base_build")/config/slam/sports_hall.yaml}"
new_config="${NEW_CONFIG:-$(source_of "$new_build")/config/slam/sports_hall.yaml}"
log="${LOG:-$root/tests/data/regression/sports_hall.lcm}"
for f in "$base_config" "$new_config" "$log"; do [ -f "$f" ] || { echo "bench-compare: no file $f" >&2; exit 2; }; done
echo "base: $base_build, config $base_config"
echo "new:  $new_build, config $new_config"
echo "log:  $log"
rounds=${ROUNDS:-3}; out="$(mktemp -d)"; trap 'rm -rf "$out"' EXIT
filter='^BM_FilterStep(FastSlam1)?/(cow|hungarian|ml)/M:(10|100)/'
for r in $(seq "$rounds"); do
  for b in base new; do
    dir=$base; config=$base_config
    [ $b = new ] && dir=$new && config=$new_config
    "$dir/bench_fastslam" --benchmark_filter="$filter" --benchmark_format=json --benchmark_out="$out"/fs.$b.$r.json \
      --benchmark_out_format=json > /dev/null 2> "$out"/fs.$b.$r.err ||
      { echo "bench-compare: $dir/bench_fastslam failed:" >&2; tail -5 "$out"/fs.$b.$r.err >&2; exit 1; }
    "$dir/bench_replay" --log "$log" --config "$config" --reps 3 --json "$out"/br.$b.$r.json > /dev/null 2> "$out"/br.$b.$r.err ||
      { echo "bench-compare: $dir/bench_replay failed (does it accept $config?):" >&2; tail -5 "$out"/br.$b.$r.err >&2; exit 1; }
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
ratios = []
print(f"{'benchmark':55s} {'base':>10s} {'new':>10s} {'new/base':>8s}")
for base, new, unit in ((fb, fn, "ms"), (rb, rn, "ms/frame")):
    for k in base:
        if k not in new:
            print(f"{k:55s} only in the base build: left out")
            continue
        a, b = statistics.median(base[k]), statistics.median(new[k])
        ratios.append(b / a)
        print(f"{k:55s} {a:10.3f} {b:10.3f} {b / a:8.3f}  ({unit}, cpu, median of {rounds})")
    for k in new:
        if k not in base:
            print(f"{k:55s} only in the new build: left out")
gm = math.exp(sum(math.log(x) for x in ratios) / len(ratios))
print(f"geometric mean new/base over {len(ratios)} benchmarks: {gm:.3f} (range {min(ratios):.3f}-{max(ratios):.3f})")
PY
