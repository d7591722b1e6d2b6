#!/usr/bin/env bash
# Everything a fresh machine needs before running omnislam: Debian packages, a multicast route,
# and a build (into build/ or $OMNISLAM_BUILD_DIR). Shared by run-default.sh and run-tests.sh.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/check-multicast.sh"
bash "$root/scripts/build.sh"
