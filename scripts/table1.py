#!/usr/bin/env python3
"""Table I of paper 000 from the files scripts/reproduce-table1.sh writes: per seed and association
method the landmark error (mean, max), the robot's position and heading error, the lights found,
duplicated landmarks (estimated landmarks left unmatched to a true light within the gate: the
second copy of a light re-initialised after a failed loop closure, or a ghost) and loops closed.

A loop is closed at a return to the start (the true path comes back within 0.5 m of its first
position after having been more than 3 m away) when the estimated position there is within 0.5 m
of the truth and no landmark is duplicated (a failed closure re-initialises the revisited lights).

usage: table1.py DIR SEED [SEED ...]"""
import json
import math
import sys


def read_tum(path):
    out = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            out.append((v[0], v[1], v[2]))
    return out


def returns_to_start(truth):
    t0, x0, y0 = truth[0]
    away, inside, times = False, [], []
    for t, x, y in truth:
        d = math.hypot(x - x0, y - y0)
        if d > 3.0:
            away = True
        if away and d < 0.5:
            inside.append((d, t))
        elif inside:
            times.append(min(inside)[1])
            inside, away = [], d > 3.0
    if inside:
        times.append(min(inside)[1])
    return times


def error_at(slam, truth, t):
    s = min(slam, key=lambda p: abs(p[0] - t))
    g = min(truth, key=lambda p: abs(p[0] - t))
    return math.hypot(s[1] - g[1], s[2] - g[2])


def row(d, method, seed):
    e = json.load(open(f"{d}/eval-{method}-seed{seed}.json"))
    slam = read_tum(f"{d}/slam-{method}-seed{seed}.slam.tum")
    truth = read_tum(f"{d}/slam-{method}-seed{seed}.truth.tum")
    rets = returns_to_start(truth)
    dup = e["landmarks_spurious"]
    closed = sum(1 for t in rets if error_at(slam, truth, t) < 0.5 and dup == 0)
    e["loops"] = f"{closed}/{len(rets)}"
    e["return_err"] = "/".join(f"{error_at(slam, truth, t):.2f}" for t in rets)
    return e


def main():
    d, seeds = sys.argv[1], sys.argv[2:]
    hdr = ("| seed | method | landmark mean / max [m] | position RMSE / max [m] | heading RMSE [deg] "
           "| lights | duplicated | loops closed | error at returns [m] | bar |")
    print(hdr)
    print("|" + "---|" * 10)
    summary = {"hungarian": [], "ml": []}
    for s in seeds:
        for m in ("hungarian", "ml"):
            e = row(d, m, s)
            ok = e["landmark_mean_err_m"] <= 0.48 and e["landmark_max_err_m"] <= 1.05 and e["landmarks_matched"] == e["landmarks_truth"]
            summary[m].append((e, ok))
            print(f"| {s} | {'Hungarian' if m == 'hungarian' else 'ML'} | {e['landmark_mean_err_m']:.3f} / {e['landmark_max_err_m']:.3f} "
                  f"| {e['ate_rmse_m']:.3f} / {e['ate_max_m']:.3f} | {math.degrees(e['heading_rmse_rad']):.2f} "
                  f"| {e['landmarks_matched']}/{e['landmarks_truth']} | {e['landmarks_spurious']} | {e['loops']} "
                  f"| {e['return_err']} | {'pass' if ok else 'FAIL'} |")
    print()
    def ms(vals):
        n = len(vals)
        mu = sum(vals) / n
        sd = math.sqrt(sum((v - mu) ** 2 for v in vals) / (n - 1)) if n > 1 else 0.0
        return f"{mu:.3f} +- {sd:.3f}"

    print("Figs. 7-8 of the paper (per-run figures over the seeds, mean +- standard deviation):")
    print()
    print("| method | landmark mean [m] | landmark max [m] | position RMSE [m] | position max [m] | heading RMSE [deg] |")
    print("|---|---|---|---|---|---|")
    for m, rows in summary.items():
        e = [r[0] for r in rows]
        print(f"| {'Hungarian' if m == 'hungarian' else 'ML'} | {ms([x['landmark_mean_err_m'] for x in e])} "
              f"| {ms([x['landmark_max_err_m'] for x in e])} | {ms([x['ate_rmse_m'] for x in e])} "
              f"| {ms([x['ate_max_m'] for x in e])} | {ms([math.degrees(x['heading_rmse_rad']) for x in e])} |")
    print()
    for m, rows in summary.items():
        n = len(rows)
        mean = sum(r[0]["landmark_mean_err_m"] for r in rows) / n
        worst = max(r[0]["landmark_max_err_m"] for r in rows)
        ate = sum(r[0]["ate_rmse_m"] for r in rows) / n
        dups = sum(r[0]["landmarks_spurious"] for r in rows)
        passed = sum(1 for r in rows if r[1])
        closed = sum(int(r[0]["loops"].split("/")[0]) for r in rows)
        total = sum(int(r[0]["loops"].split("/")[1]) for r in rows)
        print(f"- {'Hungarian' if m == 'hungarian' else 'ML'}: {passed}/{n} seeds within the paper's bar "
              f"(mean <= 0.48 m, max <= 1.05 m, all 16 lights); landmark mean of means {mean:.3f} m, worst max "
              f"{worst:.3f} m; mean position RMSE {ate:.3f} m; {dups} duplicated landmarks; loops closed {closed}/{total}")


if __name__ == "__main__":
    main()
