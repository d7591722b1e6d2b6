#!/usr/bin/env python3
"""Table of scripts/reproduce-room.sh: per seed, the paper's method (FastSLAM 1.0 + ML) and ours
(FastSLAM 2.0 + Hungarian) on the simulated room, 2D errors. Bar (paper 002): robot path error and
landmark error below 0.30 m (one 30 x 30 cm floor tile); here: ATE RMSE and mean landmark error.
usage: room_table.py DIR SEED [SEED ...]"""
import json
import math
import sys


def main():
    d, seeds = sys.argv[1], sys.argv[2:]
    names = {"paper": "FastSLAM 1.0 + ML (paper 002)", "ours": "FastSLAM 2.0 + Hungarian"}
    print("| seed | method | path RMSE / max [m] | heading RMSE [deg] | landmark mean / max [m] | lines matched / true | spurious | dead reckoning RMSE [m] | bar |")
    print("|" + "---|" * 9)
    rows = {"paper": [], "ours": []}
    for s in seeds:
        for m in ("paper", "ours"):
            e = json.load(open(f"{d}/eval-{m}-seed{s}.json"))
            # omnislam-eval writes a landmark error of 0 when no line was matched: that is no pass.
            ok = e["ate_rmse_m"] < 0.30 and e["landmarks_matched"] > 0 and e["landmark_mean_err_m"] < 0.30
            rows[m].append((e, ok))
            print(f"| {s} | {names[m]} | {e['ate_rmse_m']:.3f} / {e['ate_max_m']:.3f} | {math.degrees(e['heading_rmse_rad']):.2f} "
                  f"| {e['landmark_mean_err_m']:.3f} / {e['landmark_max_err_m']:.3f} | {e['landmarks_matched']} / {e['landmarks_truth']} "
                  f"| {e['landmarks_spurious']} | {e.get('dr_ate_rmse_m', float('nan')):.3f} | {'pass' if ok else 'FAIL'} |")
    print()
    for m, r in rows.items():
        n = len(r)
        es = [x[0] for x in r]
        mean = lambda k: sum(x.get(k, float("nan")) for x in es) / n
        print(f"- {names[m]}: {sum(1 for x in r if x[1])}/{n} seeds with path RMSE and mean landmark error < 0.30 m; "
              f"mean path RMSE {mean('ate_rmse_m'):.3f} m (worst {max(x['ate_rmse_m'] for x in es):.3f}), mean landmark error "
              f"{mean('landmark_mean_err_m'):.3f} m (worst {max(x['landmark_mean_err_m'] for x in es):.3f}), lines matched "
              f"{mean('landmarks_matched'):.1f} of {es[0]['landmarks_truth']}, spurious {sum(x['landmarks_spurious'] for x in es)}; "
              f"dead reckoning RMSE {mean('dr_ate_rmse_m'):.3f} m")


if __name__ == "__main__":
    main()
