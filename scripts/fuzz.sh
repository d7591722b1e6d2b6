#!/usr/bin/env bash
# Runs every libFuzzer target of tests/fuzz for a fixed time and prints, per target, the executions,
# the coverage (edges), the findings, and the peak memory (docs/design/fuzzing.md).
#
#   scripts/fuzz.sh [--seconds-per-target N] [--targets a,b,...] [--seed S] [--build-only] [--make-seeds]
#
# Builds the fuzz executables in build-fuzz/ (clang-14, -fsanitize=fuzzer,address,undefined:
# OMNISLAM_FUZZ=ON, only the fuzz_* targets). Each target runs N seconds (default 60) on a working
# corpus build-fuzz/fuzz-work/TARGET/corpus started from the seeds of tests/fuzz/corpus/TARGET (read
# only), with the target's dictionary tests/fuzz/dict/TARGET.dict when there is one. Per input:
# -rss_limit_mb=2048 (the malloc limit too), -timeout=10 s, -max_len (the table below): an input that
# takes more is a finding, not slowness. A finding (crash, sanitizer report, leak, timeout, out of
# memory) is written by libFuzzer as a file and copied to tests/fuzz/regressions/TARGET/ (a slow-unit
# file, libFuzzer's slowest input under the limit, stays in build-fuzz/fuzz-work/), where the
# normal suite's fuzz_test_regressions replays it: commit it with the fix. Exit 1 when any target
# had a finding. --make-seeds rewrites the seed corpora from the project's files (then exits).
# --seed S (a whole number >= 1) fixes libFuzzer's random seed, so that a run is repeatable up to
# its time limit (the CI's smoke run uses 1); without it libFuzzer draws one (the long runs' way of
# exploring), and prints it first in build-fuzz/fuzz-work/TARGET/last-run.log.
# OMNISLAM_FUZZ_BUILD_DIR (default build-fuzz), OMNISLAM_FUZZ_CXX / _CC (default clang++-14 / clang-14).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
build="${OMNISLAM_FUZZ_BUILD_DIR:-$root/build-fuzz}"
seconds=60
only=""
seed=""
build_only=0
make_seeds=0
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds-per-target) seconds="${2:?--seconds-per-target needs a number}"; shift 2 ;;
    --targets) only="${2:?--targets needs a list}"; shift 2 ;;
    --seed) seed="${2:?--seed needs a number}"; shift 2 ;;
    --build-only) build_only=1; shift ;;
    --make-seeds) make_seeds=1; shift ;;
    -h | --help) awk 'NR == 1 { next } !/^#/ { exit } { sub(/^# ?/, ""); print }' "$0"; exit 0 ;;
    *) echo "fuzz.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ "$seconds" =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: --seconds-per-target must be a whole number >= 1, got '$seconds'" >&2; exit 2; }
[ -z "$seed" ] || [[ "$seed" =~ ^[1-9][0-9]{0,8}$ ]] || { echo "fuzz.sh: --seed must be a whole number in [1, 999999999], got '$seed'" >&2; exit 2; }

# Every target with its -max_len (bytes): binary formats get room for their seeds, text files 16 KiB.
declare -A MAX_LEN=(
  [lcm_messages]=65536 [lcm_log]=65536 [image_header]=65536 [image_decode]=65536 [calibration]=16384
  [ocamcalib]=16384 [slam_config]=16384 [world_config]=16384 [features_config]=16384 [launch_file]=16384
  [saved_map]=16384 [checkpoint]=65536 [mrclam]=16384 [wheel_csv]=16384
)
ALL=(lcm_messages lcm_log image_header image_decode calibration ocamcalib slam_config world_config
  features_config launch_file saved_map checkpoint mrclam wheel_csv)

configure_and_build() {
  local cxx="${OMNISLAM_FUZZ_CXX:-clang++-14}" cc="${OMNISLAM_FUZZ_CC:-clang-14}"
  command -v "$cxx" > /dev/null || { echo "fuzz.sh: $cxx not found (scripts/install-deps.sh installs clang-14)" >&2; exit 1; }
  mkdir -p "$build"
  CXX="$cxx" CC="$cc" cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DOMNISLAM_FUZZ=ON \
    -DOMNISLAM_SANITIZE=fuzzer-no-link,address,undefined -DOMNISLAM_BUILD_BENCH=OFF > "$build.configure.log" 2>&1 \
    || { cat "$build.configure.log"; exit 1; }
  cmake --build "$build" -j"$(nproc)" --target fuzz_all fuzz_make_seeds > "$build.build.log" 2>&1 \
    || { tail -40 "$build.build.log"; exit 1; }
}

# The seed corpora: the binary seeds from fuzz_make_seeds, the text seeds copied from the project.
make_seed_corpora() {
  local c="$root/tests/fuzz/corpus" ds="$root/../shared/datasets"
  rm -rf "$c" && mkdir -p "$c"
  "$build/bin/fuzz_make_seeds" "$c"
  mkdir -p "$c"/{calibration,ocamcalib,slam_config,world_config,features_config,launch_file,mrclam,wheel_csv}
  cp config/cameras/*.yaml "$c/calibration/"
  # The XML form, as cv::FileStorage writes it (the project has no XML calibration of its own).
  printf '%s\n' '<?xml version="1.0"?>' '<opencv_storage>' '<image_width>1280</image_width>' \
    '<image_height>960</image_height>' '<camera_matrix type_id="opencv-matrix">' '  <rows>3</rows>' \
    '  <cols>3</cols>' '  <dt>d</dt>' '  <data>' '    4.005e+02 2.5e-01 6.401e+02' \
    '    0. 4.015e+02 4.802e+02 0. 0. 1.</data></camera_matrix>' \
    '<distortion_coefficients type_id="opencv-matrix">' '  <rows>1</rows>' '  <cols>4</cols>' '  <dt>d</dt>' \
    '  <data>' '    -3.0e-01 1.0e-01 1.0e-03 -2.0e-03</data></distortion_coefficients>' '<xi>9.6e-01</xi>' \
    '</opencv_storage>' > "$c/calibration/opencv-omnidir.xml"
  cp config/slam/*.yaml "$c/slam_config/"
  cp config/worlds/*.yaml "$c/world_config/"
  cp config/features/*.yaml "$c/features_config/"
  cp config/launch/*.yaml "$c/launch_file/"
  if [ -d "$ds/omni-images" ]; then  # the OCamCalib sample of the shared datasets (docs/results/calibration-samples.md)
    cp "$ds/omni-images/ocamcalib-calib_results.txt" "$c/ocamcalib/calib_results.txt"
    cp "$ds/omni-images/ocamcalib-calib_results.txt" "$c/calibration/calib_results.txt"
  fi
  local m="$ds/mrclam/MRCLAM_Dataset6" k=0 f
  if [ -d "$m" ]; then  # the first lines of each kind of MRCLAM file; the first byte picks the reader
    for f in Robot1_Odometry Robot1_Groundtruth Robot1_Measurement Landmark_Groundtruth Barcodes; do
      { printf "\\x$(printf %02x "$k")"; head -c 3000 "$m/$f.dat" | sed '$d'; } > "$c/mrclam/$f"
      k=$((k + 1))
    done
  fi
  printf '# utime,v_mps,omega_radps\nutime,v_mps,omega_radps\n1700000000000000,0.27,0\n1700000000020000,0.27,0.1\n' \
    > "$c/wheel_csv/two_rows.csv"
  du -sh "$c"
}

# One target for $seconds: prints its row of the table; returns 1 on a finding.
run_target() {
  local t="$1" exe="$build/bin/fuzz_$1" work="$build/fuzz-work/$1" extra=() log
  [ -x "$exe" ] || { echo "fuzz.sh: no executable $exe" >&2; return 2; }
  mkdir -p "$work/corpus" "$work/artifacts" "$work/tmp"
  rm -f "$work/artifacts"/*
  [ -f "$root/tests/fuzz/dict/$t.dict" ] && extra=(-dict="$root/tests/fuzz/dict/$t.dict")
  [ -z "$seed" ] || extra+=(-seed="$seed")
  log="$work/last-run.log"
  local start=$SECONDS rc=0
  TMPDIR="$work/tmp" "$exe" "$work/corpus" "$root/tests/fuzz/corpus/$t" "${extra[@]}" \
    -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 -max_len="${MAX_LEN[$t]}" \
    -print_final_stats=1 -artifact_prefix="$work/artifacts/" > "$log" 2>&1 || rc=$?
  local execs edges rss findings=0 f
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  rss=$(grep -o 'stat::peak_rss_mb: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  edges=$(grep -o ' cov: [0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  for f in "$work/artifacts"/*; do
    [ -f "$f" ] || continue
    case "$(basename "$f")" in  # libFuzzer's slowest input so far: under the time limit, not a finding
      slow-unit-*) echo "fuzz.sh: $t: slow input $(basename "$f") kept in $work/artifacts (log: $log)" >&2; continue ;;
    esac
    findings=$((findings + 1))
    mkdir -p "$root/tests/fuzz/regressions/$t"
    cp "$f" "$root/tests/fuzz/regressions/$t/"
    echo "fuzz.sh: $t: finding $(basename "$f") -> tests/fuzz/regressions/$t/ (log: $log)" >&2
  done
  [ "$rc" = 0 ] || [ "$findings" -gt 0 ] || { findings=1; echo "fuzz.sh: $t: exit $rc without an artifact (log: $log)" >&2; }
  printf '%-16s %12s %8s %9s %10s %6s\n' "$t" "${execs:-?}" "${edges:-?}" "$findings" "${rss:-?}" "$((SECONDS - start))"
  [ "$findings" = 0 ]
}

configure_and_build
if [ "$make_seeds" = 1 ]; then make_seed_corpora; exit 0; fi
[ "$build_only" = 0 ] || exit 0
targets=("${ALL[@]}")
[ -z "$only" ] || IFS=, read -r -a targets <<< "$only"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/tests/support/lsan.supp:print_suppressions=0}"
printf '%-16s %12s %8s %9s %10s %6s\n' target executions edges findings peak_MB s
status=0
for t in "${targets[@]}"; do
  [ -n "${MAX_LEN[$t]:-}" ] || { echo "fuzz.sh: unknown target '$t' (known: ${ALL[*]})" >&2; exit 2; }
  run_target "$t" || status=1
done
exit "$status"
