#!/usr/bin/env python3
"""Table of research/graph-oracle-worlds.sh's output: the pass rate of the true-association graph on
the criteria it can be scored on (landmark mean <= 0.30 m, max <= 0.8 m, position RMSE <= half of
dead reckoning's), the distributions, and the failing worlds with their odometry scale error (the
world's info) beside the solved map's scale error about the start."""
import glob
import json
import statistics as st
import sys


def rows(d):
    out = []
    for g in glob.glob(d + "/graph-*.json"):
        s = int(g.rsplit("-", 1)[1].split(".")[0])
        gj, e = json.load(open(g)), json.load(open(f"{d}/eval-{s}.json"))
        info = json.load(open(f"{d}/world-{s}.info.json"))
        ok = (gj["graph_lamp_mean_m"] <= 0.30 and gj["graph_lamp_max_m"] <= 0.8
              and gj["graph_position_rmse_m"] <= 0.5 * e["dr_ate_rmse_m"])
        out.append(dict(seed=s, ok=ok, mean=gj["graph_lamp_mean_m"], max=gj["graph_lamp_max_m"],
                        rmse=gj["graph_position_rmse_m"], dr=e["dr_ate_rmse_m"],
                        odo_scale=info["odometry_scale_error"], map_scale=gj["graph_scale_about_start"] - 1))
    return sorted(out, key=lambda r: r["seed"])


def main():
    r = rows(sys.argv[1])
    n = len(r)
    if n == 0:
        sys.exit("graph_oracle_table: no graph-*.json in " + sys.argv[1])
    print(f"{sum(x['ok'] for x in r)}/{n} pass (landmark mean <= 0.30 m, max <= 0.8 m, position RMSE <= DR / 2)")
    for k in ("mean", "max", "rmse"):
        v = sorted(x[k] for x in r)
        print(f"{k}: median {st.median(v):.3f} p90 {v[max(0, int(0.9 * n) - 1)]:.3f} max {v[-1]:.3f}")
    if n > 2:
        print("map scale error against odometry scale error: correlation %.3f"
              % st.correlation([x["odo_scale"] for x in r], [x["map_scale"] for x in r]))
    for x in r:
        if not x["ok"]:
            print("  world %d: mean %.3f max %.3f rmse %.3f (DR %.2f) odometry scale %+.4f map scale %+.4f"
                  % (x["seed"], x["mean"], x["max"], x["rmse"], x["dr"], x["odo_scale"], x["map_scale"]))


if __name__ == "__main__":
    main()
