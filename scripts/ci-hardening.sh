#!/usr/bin/env bash
# The CI's hardening step (opt-in: OMNISLAM_CI_FUZZ=1 bash scripts/run-tests.sh runs it after the
# suite; docs/design/fuzzing.md): the `unit` label on an AddressSanitizer + UndefinedBehaviorSanitizer
# build that builds only the unit tests (target unit_tests, in build-sanitize/), then every fuzz target
# for a short fixed time with a fixed seed (scripts/fuzz.sh --seed 1, OMNISLAM_CI_FUZZ_SECONDS per target,
# default 10; new findings come from the long runs, which draw their seeds). Prints the
# wall time of each part; exit 1 when either fails.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
seconds="${OMNISLAM_CI_FUZZ_SECONDS:-10}"
sbuild="${OMNISLAM_SANITIZE_BUILD_DIR:-$root/build-sanitize}"
status=0

t0=$SECONDS
mkdir -p "$sbuild"
cmake -S "$root" -B "$sbuild" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DOMNISLAM_SANITIZE=address,undefined \
  -DOMNISLAM_BUILD_BENCH=OFF > "$sbuild.configure.log" 2>&1 || { cat "$sbuild.configure.log"; exit 1; }
cmake --build "$sbuild" -j"$(nproc)" --target unit_tests > "$sbuild.build.log" 2>&1 \
  || { tail -40 "$sbuild.build.log"; exit 1; }
echo "ci-hardening: sanitizer build of the unit tests: $((SECONDS - t0)) s"
t1=$SECONDS
(
  export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:detect_stack_use_after_return=1:strict_string_checks=1}"
  export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
  export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/tests/support/lsan.supp:print_suppressions=0}"
  cd "$sbuild" && ctest --output-on-failure -j"$(nproc)" -L unit
) || status=1
echo "ci-hardening: unit label under ASan + UBSan: $((SECONDS - t1)) s"
t2=$SECONDS
bash scripts/fuzz.sh --seconds-per-target "$seconds" --seed 1 || status=1
echo "ci-hardening: fuzz build and $seconds s per target: $((SECONDS - t2)) s; all: $((SECONDS - t0)) s"
exit "$status"
