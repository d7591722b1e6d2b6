"""Runs one evaluation function per generated world on a pool of threads (the scripts that evaluate
world families: evaluate-relocalisation.py, evaluate-map-merge.py).

run_worlds(fn, worlds, jobs, tag) calls fn(family, seed) for each (family, seed) of worlds, at most
jobs at a time, and returns (results, failed): the return values in the order of worlds, and one
line "family seed: reason" per world whose function raised (printed on stderr with the tag), so that
one world that fails is reported and the others still count.
"""
import sys
from concurrent.futures import ThreadPoolExecutor


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
