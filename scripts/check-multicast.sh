#!/usr/bin/env bash
# LCM's UDP multicast needs a route for 224.0.0.0/4. Most machines have one through the default
# route; a machine without any (containers, offline hosts) gets one on the loopback interface.
set -euo pipefail
if ip route get 239.255.76.67 >/dev/null 2>&1; then
  exit 0
fi
echo "check-multicast: no route for multicast; adding 224.0.0.0/4 on lo (needs root)" >&2
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO ip link set lo multicast on
$SUDO ip route add 224.0.0.0/4 dev lo
