#!/usr/bin/env python3
"""The table of research/oracle-worlds.sh: per variant (a folder of DIR holding eval-hungarian-SEED.json
and world-SEED.info.json, as scripts/evaluate-worlds.sh writes them), the pass rate on issue 45's
criteria computed by scripts/worlds_table.py's own code, how often each criterion fails, the medians
of the figures, the noise-free bar (map rotation about the start <= 0.3 deg and landmark mean
<= 0.05 m, from the research program's fit-SEED.json) and, when both were run, whether the
recomposed filter gave omnislam-slam's JSON. Writes DIR/oracle-table.md and DIR/oracle-summary.json.

usage: oracle_table.py DIR --family F --seeds FIRST LAST --rate-hz R --variants V [V ...]"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import worlds_table as wt  # noqa: E402  (the criteria and figures of evaluate-worlds.sh)

LABEL = {"filter": "(a) shipped filter", "truth-assoc": "(b) truth association", "exact": "(c) exact inputs",
         "exact-truth-assoc": "(d) exact + truth assoc.", "true-map": "(e) true map, localisation",
         "truth-birth": "(f) truth assoc. + true birth", "exact-truth-birth": "(g) exact + truth assoc. + true birth",
         "shipped": "omnislam-slam", "shipped-exact": "omnislam-slam, exact"}
MEDIANS = [("landmark_mean_m", "landmark mean [m]", "{:.3f}"), ("landmark_max_m", "landmark max [m]", "{:.3f}"),
           ("mapped_fraction", "mapped / seen 3x", "{:.3f}"), ("heading_rmse_deg", "heading RMSE [deg]", "{:.2f}"),
           ("ate_rmse_m", "position RMSE [m]", "{:.3f}"), ("rmse_ratio", "RMSE / DR RMSE", "{:.3f}")]


def fit_rows(vdir, seeds, rows):
    """Per world: |map rotation| and the noise-free bar (rotation <= 0.3 deg and landmark mean <= 0.05 m)."""
    out = []
    for s, r in zip(seeds, rows):
        p = os.path.join(vdir, f"fit-{s}.json")
        if not os.path.exists(p) or "landmark_mean_m" not in r:
            continue
        fit = json.load(open(p))
        rot = abs(fit["map_rotation_deg"])
        seen3, starved = fit.get("lamps_seen_3"), fit.get("lamps_seen_3_parallax_starved")
        out.append({"seed": s, "rotation_deg": rot, "bar": rot <= 0.3 and r["landmark_mean_m"] <= 0.05,
                    "derotated_m": fit["fit_mean_derotated_xy_m"] if fit["fit_matched"] else None,
                    "mappable": None if starved is None else (seen3 - starved) >= 0.95 * seen3})
    return out


def variant_summary(d, v, seeds):
    vdir = os.path.join(d, v)
    rows = [wt.world_row(vdir, "hungarian", s) for s in seeds]
    agg = wt.aggregate(rows)
    fits = fit_rows(vdir, seeds, rows)
    agg["noise_free_bar"] = sum(f["bar"] for f in fits) if fits else None
    agg["rotation_median_deg"] = wt.quantile([f["rotation_deg"] for f in fits], 0.5) if fits else None
    agg["derotated_median_m"] = wt.quantile([f["derotated_m"] for f in fits], 0.5) if fits else None
    known = [f["mappable"] for f in fits if f["mappable"] is not None]
    agg["parallax_allows_95"] = sum(known) if known else None
    # The four map criteria without the position one (meaningless with exact odometry: its RMSE is 0).
    agg["passed_map_criteria"] = sum(1 for r in rows if "criteria" in r and all(r["criteria"][:4]))
    return rows, agg


def same_json(d, a, b, seeds):
    """Worlds where variant a's eval JSON equals variant b's (the recomposition check)."""
    n = 0
    for s in seeds:
        pa, pb = (os.path.join(d, x, f"eval-hungarian-{s}.json") for x in (a, b))
        n += os.path.exists(pa) and os.path.exists(pb) and json.load(open(pa)) == json.load(open(pb))
    return n


def table(aggs, variants, n):
    cols = [LABEL.get(v, v) for v in variants]
    lines = ["| | " + " | ".join(cols) + " |", "|---|" + "---|" * len(variants)]
    lines.append("| **pass (all criteria)** | " + " | ".join(f"**{aggs[v]['passed']}/{n}**" for v in variants) + " |")
    lines.append("| pass, the four map criteria only | " + " | ".join(f"{aggs[v]['passed_map_criteria']}" for v in variants) + " |")
    for cname, _ in wt.CRITERIA:
        lines.append(f"| {cname} | " + " | ".join(f"{aggs[v]['criteria'][cname]}" for v in variants) + " |")
    for k, label, f in MEDIANS:
        # With exact odometry dead reckoning's RMSE is 0: the ratio says nothing.
        cells = ["n/a" if k == "rmse_ratio" and "exact" in v else wt.fmt(aggs[v]["figures"][k]["median"], f) for v in variants]
        lines.append(f"| {label}, median | " + " | ".join(cells) + " |")
    lines.append("| map rotation about the start [deg], median | " +
                 " | ".join(wt.fmt(aggs[v]["rotation_median_deg"], "{:.2f}") for v in variants) + " |")
    lines.append("| landmark mean (x-y) after removing that rotation [m], median | " +
                 " | ".join(wt.fmt(aggs[v]["derotated_median_m"], "{:.3f}") for v in variants) + " |")
    lines.append("| rotation <= 0.3 deg and landmark mean <= 0.05 m | " +
                 " | ".join("n/a" if aggs[v]["noise_free_bar"] is None else str(aggs[v]["noise_free_bar"]) for v in variants) + " |")
    lines.append("| >= 95 % of lamps seen 3x have >= NCROSS_valid pairs of rays >= ANG_min apart | " +
                 " | ".join("n/a" if aggs[v]["parallax_allows_95"] is None else str(aggs[v]["parallax_allows_95"]) for v in variants) + " |")
    return "\n".join(lines)


def main():
    ap = wt.world_set_parser(__doc__.splitlines()[0])
    ap.add_argument("--variants", nargs="+", required=True)
    a = ap.parse_args()
    seeds = list(range(a.seeds[0], a.seeds[1] + 1))
    res = {v: variant_summary(a.dir, v, seeds) for v in a.variants}
    aggs = {v: res[v][1] for v in a.variants}
    text = (f"{a.family}, {len(seeds)} worlds (seeds {a.seeds[0]}..{a.seeds[1]}), frames at {a.rate_hz} Hz, "
            f"config/slam/sports_hall.yaml, Hungarian; counts = worlds meeting each criterion\n\n" + table(aggs, a.variants, len(seeds)))
    for x, y in (("filter", "shipped"), ("exact", "shipped-exact")):
        if x in a.variants and y in a.variants:
            text += f"\n\ncheck: {x} gives omnislam-slam's eval JSON in {same_json(a.dir, x, y, seeds)}/{len(seeds)} worlds"
    print(text)
    with open(os.path.join(a.dir, "oracle-table.md"), "w") as f:
        f.write(text + "\n")
    summary = {"family": a.family, "seeds": a.seeds, "rate_hz": a.rate_hz,
               "variants": {v: {"aggregate": res[v][1], "worlds": res[v][0]} for v in a.variants}}
    with open(os.path.join(a.dir, "oracle-summary.json"), "w") as f:
        json.dump(wt.strict(summary), f, indent=1, allow_nan=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
