#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds, and runs every test through CTest.
# Long soaks are opt-in: OMNISLAM_SOAK=1 bash scripts/run-tests.sh. Extra arguments go to ctest.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bash scripts/prepare.sh
build="${OMNISLAM_BUILD_DIR:-$root/build}"
exclude=()
if [ "${OMNISLAM_SOAK:-0}" != "1" ]; then
  exclude=(-LE soak)
fi
cd "$build"
ctest --output-on-failure -j"$(nproc)" "${exclude[@]}" "$@"
