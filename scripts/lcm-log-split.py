#!/usr/bin/env python3
"""lcm-log-split.py — split an LCM log into the events of some channels and the rest.

Usage: scripts/lcm-log-split.py IN.lcm CHANNEL[,CHANNEL...] SELECTED.lcm REST.lcm

Each output is a valid LCM log of the events it holds, in their order, with event numbers
renumbered 0, 1, 2, ... (as the SLAM replay numbers its output). The regression guard
(check-replay-regression.sh) digests a replay without SLAM_HEALTH, so that a log written before
the channel existed compares byte for byte, and SLAM_HEALTH on its own. Standard library only;
exit 2 on a log it cannot read.
"""
import struct
import sys

SYNC = 0xEDA1DA01
HEADER = struct.Struct(">IqqII")  # sync, event number, timestamp, channel length, data length


def events(data):
    i = 0
    while i < len(data):
        if i + HEADER.size > len(data):
            raise ValueError(f"truncated event header at byte {i}")
        sync, _, ts, clen, dlen = HEADER.unpack_from(data, i)
        if sync != SYNC:
            raise ValueError(f"no sync word at byte {i}")
        i += HEADER.size
        if i + clen + dlen > len(data):
            raise ValueError(f"truncated event at byte {i}")
        yield ts, data[i:i + clen], data[i + clen:i + clen + dlen]
        i += clen + dlen


def main(argv):
    if len(argv) != 5:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    channels = {c.encode() for c in argv[2].split(",")}
    try:
        with open(argv[1], "rb") as f:
            data = f.read()
        outs = [bytearray(), bytearray()]
        counts = [0, 0]
        for ts, ch, payload in events(data):
            k = 0 if ch in channels else 1
            outs[k] += HEADER.pack(SYNC, counts[k], ts, len(ch), len(payload)) + ch + payload
            counts[k] += 1
    except (OSError, ValueError) as e:
        print(f"lcm-log-split: {argv[1]}: {e}", file=sys.stderr)
        return 2
    for path, out in zip(argv[3:5], outs):
        with open(path, "wb") as f:
            f.write(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
