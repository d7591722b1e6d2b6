#!/usr/bin/env python3
"""Copies the events of chosen channels within a time window from one LCM log into a new one.

Used to cut small fixtures (the replay regression guard, tests/data/regression/) out of full
recordings. The bytes of every kept event are unchanged; event numbers are renumbered from 0.

  python3 scripts/lcm_log_filter.py IN.lcm OUT.lcm --channels ODOMETRY,OMNI_FEATURES [--seconds 120]

--seconds keeps the events whose log timestamp is within that many seconds of the first kept one.
"""
import argparse
import struct
import sys

SYNC = 0xEDA1DA01
HEADER = struct.Struct(">IqqII")  # sync, event number, timestamp [us], channel length, data length


def events(path):
    """Yields (timestamp_us, channel bytes, data bytes) for each event of an LCM log."""
    with open(path, "rb") as f:
        blob = f.read()
    pos = 0
    while pos + HEADER.size <= len(blob):
        sync, _, utime, clen, dlen = HEADER.unpack_from(blob, pos)
        if sync != SYNC:
            raise ValueError(f"{path}: no sync word at byte {pos}")
        start = pos + HEADER.size
        end = start + clen + dlen
        if end > len(blob):
            print(f"{path}: truncated event at byte {pos}; the events before it are kept", file=sys.stderr)
            return
        yield utime, blob[start:start + clen], blob[start + clen:end]
        pos = end


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--channels", required=True, help="comma-separated channel names to keep")
    ap.add_argument("--seconds", type=float, default=0.0, help="window length from the first kept event (0 = all)")
    a = ap.parse_args()
    if a.seconds < 0:
        ap.error("--seconds must be >= 0")
    keep = {c.encode() for c in a.channels.split(",") if c}
    first = None
    n = 0
    with open(a.output, "wb") as out:
        for utime, channel, data in events(a.input):
            if channel not in keep:
                continue
            first = utime if first is None else first
            if a.seconds > 0 and utime - first > a.seconds * 1e6:
                break
            out.write(HEADER.pack(SYNC, n, utime, len(channel), len(data)) + channel + data)
            n += 1
    print(f"{a.output}: {n} events", file=sys.stderr)
    return 0 if n > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
