#!/usr/bin/env python3
"""The SLAM settings a generated world's info file (omnislam-gen-world --out-info) gives a replay.

    python3 scripts/world_settings.py WORLD.info.json [--known-ceiling]

Prints space-separated key=value pairs for omnislam-slam --set: the start pose the world was driven
from and the camera's perception limits (max range, min elevation). With --known-ceiling also the
back end's known ceiling height, as a tape measure gives it: only where every lamp hangs at one height
(within 1 cm); otherwise exits 1 naming the world and its heights. Used by scripts/evaluate-worlds.sh,
scripts/evaluate-relocalisation.py and research/*-worlds.sh.
"""
import argparse
import json
import sys


def settings(info, known_ceiling=False):
    """The key=value settings of a world's info dict; ValueError when --known-ceiling cannot apply."""
    s = [f"start_pose.x_m={info['start_x_m']!r}", f"start_pose.y_m={info['start_y_m']!r}",
         f"start_pose.theta_deg={info['start_theta_deg']!r}",
         f"filter.perception.max_range_m={info['perception_max_range_m']!r}",
         f"filter.perception.min_elevation_deg={info['min_elevation_deg']!r}"]
    if known_ceiling:
        lo, hi = info["ceiling_min_m"], info["ceiling_max_m"]
        if hi - lo > 0.01:
            raise ValueError(f"--known-ceiling: the lamps of {info.get('world', '?')} hang between "
                             f"{lo:.2f} and {hi:.2f} m, not at one height")
        s += ["backend.ceiling=known_height", f"backend.ceiling_height_m={lo!r}"]
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("info")
    ap.add_argument("--known-ceiling", action="store_true")
    a = ap.parse_args()
    with open(a.info) as f:
        info = json.load(f)
    try:
        print(" ".join(settings(info, a.known_ceiling)))
    except ValueError as e:
        sys.exit(f"world_settings: {e}")


if __name__ == "__main__":
    main()
