#!/usr/bin/env bash
# Configures and builds omnislam into build/ (or $OMNISLAM_BUILD_DIR). Extra arguments go to cmake.
# OMNISLAM_SANITIZE=address,undefined (a -fsanitize= list) makes a sanitizer build; set it with its
# own OMNISLAM_BUILD_DIR (scripts/run-tests.sh does: build-sanitize/).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${OMNISLAM_BUILD_DIR:-$root/build}"
mkdir -p "$build"  # its configure log goes beside it, before cmake would create it
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-RelWithDebInfo}" \
  -DOMNISLAM_SANITIZE="${OMNISLAM_SANITIZE:-}" "$@" > "$build.configure.log" 2>&1 \
  || { cat "$build.configure.log"; exit 1; }
cmake --build "$build" -j"$(nproc)"
