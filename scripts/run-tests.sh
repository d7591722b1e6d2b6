#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds, and runs every test through CTest.
# Long soaks are opt-in: OMNISLAM_SOAK=1 bash scripts/run-tests.sh. Extra arguments go to ctest.
# OMNISLAM_SANITIZE=1 runs the suite on an AddressSanitizer + UndefinedBehaviorSanitizer build in
# build-sanitize/ (any other value is taken as the -fsanitize= list); a report fails its test.
# OMNISLAM_CI_FUZZ=1 adds, after the suite, the sanitized unit label and a short run of every fuzz
# target (scripts/ci-hardening.sh; docs/design/fuzzing.md).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
if [ -n "${OMNISLAM_SANITIZE:-}" ]; then
  [ "$OMNISLAM_SANITIZE" = 1 ] && export OMNISLAM_SANITIZE=address,undefined
  export OMNISLAM_BUILD_DIR="${OMNISLAM_BUILD_DIR:-$root/build-sanitize}"
  export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:detect_stack_use_after_return=1:strict_string_checks=1}"
  export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
  # Leaks inside third-party libraries, each named with its reason in the file.
  export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/tests/support/lsan.supp:print_suppressions=0}"
  # ThreadSanitizer (OMNISLAM_SANITIZE=thread): a report fails its test; races inside uninstrumented
  # GLib (under LCM) are suppressed, each with its reason in the file.
  export TSAN_OPTIONS="${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tests/support/tsan.supp}"
fi
bash scripts/prepare.sh
build="${OMNISLAM_BUILD_DIR:-$root/build}"
excluded=()
[ "${OMNISLAM_SOAK:-0}" = "1" ] || excluded+=(soak)
# The sanitizers slow everything about 3x: live runs that must answer every frame at their
# speedup (label realtime) cannot; the same processes are run by the other integration tests.
[ -z "${OMNISLAM_SANITIZE:-}" ] || excluded+=(realtime)
# ctest ANDs several -LE options (a test is left out only if it matches all of them), so a caller's
# own -LE would bring the soaks back: every label exclusion goes into one alternation instead.
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    -LE | --label-exclude)
      [ $# -ge 2 ] || { echo "run-tests: $1 needs a label regex" >&2; exit 2; }
      excluded+=("$2")
      shift 2
      ;;
    *)
      args+=("$1")
      shift
      ;;
  esac
done
exclude=()
if [ ${#excluded[@]} -gt 0 ]; then
  joined="$(IFS='|'; echo "${excluded[*]}")"
  exclude=(-LE "$joined")
fi
status=0
(cd "$build" && ctest --output-on-failure -j"$(nproc)" "${exclude[@]}" "${args[@]}") || status=$?
if [ "${OMNISLAM_CI_FUZZ:-0}" = 1 ]; then
  bash scripts/ci-hardening.sh || status=1
fi
exit "$status"
