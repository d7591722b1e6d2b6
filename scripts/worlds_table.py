#!/usr/bin/env python3
"""The table of scripts/evaluate-worlds.sh from the files it writes in DIR: per association method,
the pass rate on issue 45's criteria and the median / p90 of every figure; writes DIR/summary.json
(every world's figures and the aggregates; a figure that is not finite, e.g. the landmark error of a
world with no landmark matched, is null there) and DIR/table.md, and prints the table.

Criteria (a world passes when all hold; a run that failed or produced no JSON fails):
  landmark mean error <= 0.30 m, landmark max error <= 0.8 m,
  lamps mapped (true lamps matched within the evaluation's 2 m gate) >= 95 % of the lamps the
  detector reported in >= 3 frames (omnislam-gen-world's lamps_seen_3), <= 1 spurious landmark,
  position RMSE <= half of dead reckoning's (both unaligned, from the known start pose).

usage: worlds_table.py DIR --family F --seeds FIRST LAST --rate-hz R --methods M [M ...]
                       [--wall-s S] [--worlds-run N] [--jobs J] [--extra-sets "--set K=V ..."]"""
import argparse
import json
import math
import os
import sys

CRITERIA = [
    ("landmark mean <= 0.30 m", lambda r: r["landmark_mean_m"] <= 0.30),
    ("landmark max <= 0.8 m", lambda r: r["landmark_max_m"] <= 0.8),
    (">= 95 % of lamps seen 3x mapped", lambda r: r["mapped_fraction"] >= 0.95),
    ("<= 1 spurious", lambda r: r["spurious"] <= 1),
    ("RMSE <= DR RMSE / 2", lambda r: r["ate_rmse_m"] <= 0.5 * r["dr_ate_rmse_m"]),
]
FIGURES = [  # key, label, format
    ("landmark_mean_m", "landmark mean [m]", "{:.3f}"),
    ("landmark_max_m", "landmark max [m]", "{:.3f}"),
    ("mapped_fraction", "mapped / seen 3x", "{:.3f}"),
    ("spurious", "spurious", "{:.1f}"),
    ("ate_rmse_m", "position RMSE [m]", "{:.3f}"),
    ("dr_ate_rmse_m", "dead reckoning RMSE [m]", "{:.3f}"),
    ("rmse_ratio", "RMSE / DR RMSE", "{:.3f}"),
    ("heading_rmse_deg", "heading RMSE [deg]", "{:.2f}"),
    ("assoc_precision", "association precision", "{:.3f}"),
    ("assoc_recall", "association recall", "{:.3f}"),
]


def quantile(vals, q):
    """Linear interpolation between order statistics (numpy's default). A world with no landmark
    matched has an infinite landmark error: it stays in (it sorts last), it is not dropped."""
    v = sorted(x for x in vals if x is not None and not math.isnan(x))
    if not v:
        return None
    pos = q * (len(v) - 1)
    lo = int(math.floor(pos))
    hi = min(lo + 1, len(v) - 1)
    if v[lo] == math.inf or (v[hi] == math.inf and pos > lo):
        return math.inf
    return v[lo] + (v[hi] - v[lo]) * (pos - lo)


def world_row(d, method, seed):
    info_path = os.path.join(d, f"world-{seed}.info.json")
    eval_path = os.path.join(d, f"eval-{method}-{seed}.json")
    row = {"seed": seed, "method": method, "ok": False}
    if not os.path.exists(info_path) or not os.path.exists(eval_path):
        row["error"] = "no world info" if not os.path.exists(info_path) else "run failed (see fail-*.txt)"
        return row
    info, e = json.load(open(info_path)), json.load(open(eval_path))
    seen3 = info.get("lamps_seen_3", 0)
    row.update({
        "lamps": info["lamps"], "lamps_seen_3": seen3, "frames": info.get("frames"), "path_m": info.get("path_m"),
        "landmark_mean_m": e["landmark_mean_err_m"] if e["landmarks_matched"] else math.inf,
        "landmark_max_m": e["landmark_max_err_m"] if e["landmarks_matched"] else math.inf,
        "mapped_fraction": e["landmarks_matched"] / seen3 if seen3 else 1.0,
        "spurious": e["landmarks_spurious"], "ate_rmse_m": e["ate_rmse_m"],
        "dr_ate_rmse_m": e.get("dr_ate_rmse_m", math.nan),
        "heading_rmse_deg": math.degrees(e["heading_rmse_rad"]),
        "assoc_precision": e.get("assoc_precision"), "assoc_recall": e.get("assoc_recall"),
    })
    dr = row["dr_ate_rmse_m"]
    row["rmse_ratio"] = row["ate_rmse_m"] / dr if dr and math.isfinite(dr) and dr > 0 else None
    row["criteria"] = [bool(f(row)) for _, f in CRITERIA]
    row["ok"] = all(row["criteria"])
    return row


def aggregate(rows):
    n = len(rows)
    out = {"worlds": n, "passed": sum(r["ok"] for r in rows), "failed_runs": sum("error" in r for r in rows)}
    out["pass_rate"] = out["passed"] / n if n else 0.0
    out["criteria"] = {name: sum(1 for r in rows if "criteria" in r and r["criteria"][i])
                       for i, (name, _) in enumerate(CRITERIA)}
    out["figures"] = {k: {"median": quantile([r.get(k) for r in rows], 0.5), "p90": quantile([r.get(k) for r in rows], 0.9)}
                      for k, _, _ in FIGURES}
    return out


def strict(x):
    """JSON has no infinity: a non-finite figure (no landmark matched) is written as null."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: strict(v) for k, v in x.items()}
    if isinstance(x, list):
        return [strict(v) for v in x]
    return x


def fmt(v, f):
    return "n/a" if v is None else ("inf" if v == math.inf else f.format(v))


def table(agg, methods, header):
    name = {"hungarian": "Hungarian", "ml": "ML"}
    lines = [header, "", "| figure | " + " | ".join(name[m] for m in methods) + " |",
             "|---|" + "---|" * len(methods)]
    lines.append("| **pass rate** | " + " | ".join(
        f"**{agg[m]['passed']}/{agg[m]['worlds']} ({100 * agg[m]['pass_rate']:.0f} %)**" for m in methods) + " |")
    for cname, _ in CRITERIA:
        lines.append(f"| {cname} | " + " | ".join(f"{agg[m]['criteria'][cname]}/{agg[m]['worlds']}" for m in methods) + " |")
    for k, label, f in FIGURES:
        cells = [f"{fmt(agg[m]['figures'][k]['median'], f)} / {fmt(agg[m]['figures'][k]['p90'], f)}" for m in methods]
        lines.append(f"| {label}, median / p90 | " + " | ".join(cells) + " |")
    failed = sum(agg[m]["failed_runs"] for m in methods)
    if failed:
        lines.append(f"\n{failed} run(s) failed (counted as not passing): see fail-*.txt")
    return "\n".join(lines)


def world_set_parser(description):
    """The arguments of a table over one family's worlds (DIR --family F --seeds FIRST LAST --rate-hz R),
    shared with research/oracle_table.py."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("dir")
    ap.add_argument("--family", required=True)
    ap.add_argument("--seeds", nargs=2, type=int, required=True)
    ap.add_argument("--rate-hz", required=True)
    return ap


def main():
    ap = world_set_parser(__doc__.splitlines()[0])
    ap.add_argument("--methods", nargs="+", required=True, choices=["hungarian", "ml"])
    ap.add_argument("--wall-s", type=float, default=None)
    ap.add_argument("--jobs", type=int, default=None)
    ap.add_argument("--extra-sets", default="", help="the --set options given beyond the per-world ones (named in the header)")
    ap.add_argument("--worlds-run", type=int, default=None, help="worlds run in --wall-s (the others were scored before)")
    a = ap.parse_args()
    seeds = list(range(a.seeds[0], a.seeds[1] + 1))
    rows = {m: [world_row(a.dir, m, s) for s in seeds] for m in a.methods}
    agg = {m: aggregate(rows[m]) for m in a.methods}
    header = (f"{a.family}, {len(seeds)} worlds (seeds {a.seeds[0]}..{a.seeds[1]}), frames at {a.rate_hz} Hz, "
              f"config/slam/sports_hall.yaml" + (f" with {a.extra_sets}" if a.extra_sets.strip() else ""))
    run = len(seeds) if a.worlds_run is None else a.worlds_run
    if a.wall_s and run:
        header += f"; {run} worlds run in {a.wall_s:.0f} s wall with {a.jobs} jobs ({60 * run / a.wall_s:.1f} worlds per minute)"
    text = table(agg, a.methods, header)
    print(text)
    with open(os.path.join(a.dir, "table.md"), "w") as f:
        f.write(text + "\n")
    summary = {"family": a.family, "seeds": a.seeds, "rate_hz": a.rate_hz, "wall_s": a.wall_s, "worlds_run": run, "jobs": a.jobs,
               "extra_sets": a.extra_sets,
               "criteria": [c for c, _ in CRITERIA], "aggregate": agg, "worlds": rows}
    with open(os.path.join(a.dir, "summary.json"), "w") as f:
        json.dump(strict(summary), f, indent=1, allow_nan=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
