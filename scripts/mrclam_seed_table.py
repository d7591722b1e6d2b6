#!/usr/bin/env python3
"""mrclam_seed_table.py — the spread of the MRCLAM figures over the filter's seeds.

Usage: scripts/mrclam_seed_table.py OUT_DIR --robots "1 2 3 4 5" --seeds "1 2 3"

Reads OUT_DIR/robotN.seedS.eval-aligned.json (omnislam-eval --planar --json --align, as written by
scripts/run-mrclam.sh --seeds) and prints one Markdown table: per robot, the median [min, max] over
the seeds of the aligned ATE RMSE, the aligned landmark mean error and the spurious landmarks, the
dead-reckoning aligned ATE (the same for every seed), and how many runs meet all three bars of
issue 7 (aligned ATE <= 0.4 m, landmark mean <= 0.35 m, at most 5 spurious landmarks; a run without a
matched landmark has no landmark mean and does not meet that bar). A last row pools every run.
Standard library only. Figures quoted in docs/results/mrclam.md.
"""
import argparse
import json
import math
import os
import statistics
import sys

ATE_BAR_M = 0.4
LANDMARK_BAR_M = 0.35
SPURIOUS_BAR = 5


def parse_ints(text, flag):
    try:
        values = [int(v) for v in text.split()]
    except ValueError:
        sys.exit(f"mrclam_seed_table.py: {flag} takes integers separated by spaces, got '{text}'")
    if not values:
        sys.exit(f"mrclam_seed_table.py: {flag} is empty")
    return values


def load(path):
    try:
        with open(path, encoding="utf-8") as f:
            d = json.load(f)
    except OSError as e:
        sys.exit(f"mrclam_seed_table.py: cannot read {path}: {e.strerror}")
    except json.JSONDecodeError as e:
        sys.exit(f"mrclam_seed_table.py: {path}: not JSON ({e.msg}, line {e.lineno})")
    for k in ("ate_rmse_m", "landmarks_spurious", "landmarks_matched"):
        if k not in d:
            sys.exit(f"mrclam_seed_table.py: {path}: no '{k}' (not an omnislam-eval --json output?)")
    return d


def spread(values, digits=2):
    """'median [min, max]' of the finite values, or 'n/a' when there is none."""
    v = [x for x in values if x is not None and math.isfinite(x)]
    if not v:
        return "n/a"
    def f(x):
        # Counts (digits 0) print as integers; a median between two counts keeps its half.
        if digits == 0:
            return str(int(x)) if float(x).is_integer() else f"{x:.1f}"
        return f"{x:.{digits}f}"
    return f"{f(statistics.median(v))} [{f(min(v))}, {f(max(v))}]"


def row(label, runs):
    ate = [d["ate_rmse_m"] for d in runs]
    # The landmark mean is undefined without a matched landmark (omnislam-eval then writes 0).
    lm = [d.get("landmark_mean_err_m") if d["landmarks_matched"] > 0 else None for d in runs]
    spur = [d["landmarks_spurious"] for d in runs]
    dr = [d.get("dr_ate_rmse_aligned_m") for d in runs]
    ok = sum(1 for d, l in zip(runs, lm)
             if d["ate_rmse_m"] <= ATE_BAR_M and l is not None and l <= LANDMARK_BAR_M
             and d["landmarks_spurious"] <= SPURIOUS_BAR)
    return (f"| {label} | {len(runs)} | {spread(ate)} | {spread(lm)} | {spread(spur, 0)} | "
            f"{spread(dr)} | {ok} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("--robots", required=True)
    ap.add_argument("--seeds", required=True)
    a = ap.parse_args()
    robots = parse_ints(a.robots, "--robots")
    seeds = parse_ints(a.seeds, "--seeds")
    if not os.path.isdir(a.out_dir):
        sys.exit(f"mrclam_seed_table.py: no folder {a.out_dir}")
    print("| robot | runs | SLAM ATE aligned (m) | landmark mean (m) | spurious | DR ATE aligned (m) "
          f"| runs meeting the bars ({ATE_BAR_M} m, {LANDMARK_BAR_M} m, {SPURIOUS_BAR}) |")
    print("|---|---|---|---|---|---|---|")
    pooled = []
    for r in robots:
        runs = [load(os.path.join(a.out_dir, f"robot{r}.seed{s}.eval-aligned.json")) for s in seeds]
        pooled += runs
        print(row(str(r), runs))
    if len(robots) > 1:
        print(row("all", pooled))


if __name__ == "__main__":
    main()
