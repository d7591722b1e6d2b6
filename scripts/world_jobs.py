"""What the scripts that evaluate families of generated worlds share (evaluate-relocalisation.py,
evaluate-map-merge.py).

run_worlds(fn, worlds, jobs, tag) calls fn(family, seed) for each (family, seed) of worlds, at most
jobs at a time, and returns (results, failed): the return values in the order of worlds, and one
line "family seed: reason" per world whose function raised (printed on stderr with the tag), so that
one world that fails is reported and the others still count.
run(argv, log) runs a program with its output in the file log; a non-zero exit raises RuntimeError
with the log's tail. quantile(v, q) is the nearest-rank quantile (nan when v is empty).
truth_lamps(world_yaml) lists the (x, y, z) of a world file's lights.
cut_start(stamps, family, seed, window_s) is the utime at which evaluate-relocalisation.py cuts a
world's second run (a random frame time of the drive, window_s before its end at the latest, from a
generator seeded by the world), which research/relocalisation_oracle.py cuts again.
"""
import os
import random
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import yaml


def run(argv, log):
    with open(log, "w") as f:
        r = subprocess.run(argv, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        with open(log) as f:
            tail = f.read()[-600:]
        raise RuntimeError(f"{os.path.basename(argv[0])} exited {r.returncode}: {tail}")


def quantile(v, q):
    v = sorted(v)
    return v[min(len(v) - 1, int(q * (len(v) - 1) + 0.5))] if v else float("nan")


def truth_lamps(world_yaml):
    with open(world_yaml) as f:
        return [(L["x_m"], L["y_m"], L["z_m"]) for L in yaml.safe_load(f)["lights"]["list"]]


def run_worlds(fn, worlds, jobs, tag):
    results, failed = [], []
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [(pool.submit(fn, f, s), f, s) for f, s in worlds]
        for fut, f, s in futures:
            try:
                results.append(fut.result())
            except Exception as e:  # noqa: BLE001 - any failure of one world is reported, not fatal
                failed.append(f"{f} {s}: {type(e).__name__}: {e}")
    for line in failed:
        print(f"{tag}: failed: {line}", file=sys.stderr)
    return results, failed


def cut_start(stamps, family, seed, window_s):
    """The second run's cut: a frame time (utime) drawn from the world's seed; stamps: its frame utimes."""
    rng = random.Random(seed * 7919 + len(family))
    latest = max(stamps[0], stamps[-1] - int(window_s * 1e6))
    return stamps[0] + int(rng.random() * (latest - stamps[0]))
