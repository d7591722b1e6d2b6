#!/usr/bin/env bash
# Headless check that lcm-spy, started by scripts/lcm-spy.sh under Xvfb, knows every omnislam type:
# publishes one sample on every channel, screenshots the spy window, and checks that lcm-spy
# loaded as many types as lcmtypes/ defines. Usage: scripts/check-lcm-spy.sh [SCREENSHOT.png]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${OMNISLAM_BUILD_DIR:-$root/build}"
shot="${1:-$build/lcm-spy.png}"
port=$((20000 + ($$ % 30000)))
url="udpm://239.255.76.67:$port?ttl=0"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
expected=$(ls "$root"/lcmtypes/*.lcm | wc -l)
command -v xvfb-run >/dev/null || { echo "check-lcm-spy: xvfb-run missing (bash scripts/install-deps.sh)" >&2; exit 1; }
xvfb-run -a -s "-screen 0 1400x700x24" bash -c "
  '$root/scripts/lcm-spy.sh' --lcm-url='$url' > '$log' 2>&1 &
  spy=\$!
  # lcm-spy prints 'Found N LCM types' once the JVM has scanned its class path: wait for that line
  # (up to 60 s on a loaded machine) rather than a fixed pause.
  # A spy that dies first (no X11 library for its window, a bad class path) ends the wait.
  for _ in \$(seq 1 600); do
    grep -q '^Found [0-9]* LCM types' '$log' && break
    kill -0 \$spy 2>/dev/null || break
    sleep 0.1
  done
  '$build/bin/omnislam-publish-samples' --url '$url' --duration 5 --period 0.2
  if command -v xwd >/dev/null && command -v convert >/dev/null; then
    xwd -root -silent | convert xwd:- png:'$shot'
  fi
  # It must still be running after the messages: a window that threw is not a working spy.
  kill -0 \$spy 2>/dev/null || echo 'check-lcm-spy: lcm-spy exited before the end of the check' >> '$log'
  kill \$spy 2>/dev/null || true
  wait \$spy 2>/dev/null || true
"
found=$(sed -n 's/^Found \([0-9]*\) LCM types.*/\1/p' "$log" | head -1)
sed 's/^/lcm-spy | /' "$log"
if [ "${found:-0}" -ne "$expected" ]; then
  echo "check-lcm-spy: FAILED: lcm-spy found ${found:-no} types, lcmtypes/ defines $expected" >&2
  exit 1
fi
if grep -q '^check-lcm-spy: lcm-spy exited' "$log"; then
  echo "check-lcm-spy: FAILED: lcm-spy exited while it should have been showing the messages (see above)" >&2
  exit 1
fi
echo "check-lcm-spy: lcm-spy loaded all $expected omnislam types; screenshot: $shot"
