#!/usr/bin/env bash
# Starts lcm-spy with omnislam's message types on the classpath, so that every channel is decoded.
# Usage: scripts/lcm-spy.sh [--lcm-url=URL]   (default: $LCM_DEFAULT_URL or the launch file's URL)
# Needs a display (or: xvfb-run -a scripts/lcm-spy.sh). Build first (scripts/build.sh).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
jar="${OMNISLAM_BUILD_DIR:-$root/build}/java/omnislam-lcmtypes.jar"
if [ ! -f "$jar" ]; then
  echo "lcm-spy.sh: $jar not found: build first (bash scripts/build.sh)" >&2
  exit 1
fi
url_args=("$@")
if [ ${#url_args[@]} -eq 0 ]; then
  url_args=("--lcm-url=${LCM_DEFAULT_URL:-udpm://239.255.76.67:7667?ttl=0}")
fi
# Debian's lcm-spy script passes -Xincgc, which Java 17 rejects: call the class directly.
# lcm-spy never sets SO_RCVBUF: raise net.core.rmem_default (docs/user/lcm.md) to see every image.
export CLASSPATH="$jar:/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar"
exec java -Djava.net.preferIPv4Stack=true -Xmx256m -ea -cp "$CLASSPATH" lcm.spy.Spy "${url_args[@]}"
