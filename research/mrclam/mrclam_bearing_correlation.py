#!/usr/bin/env python3
"""mrclam_bearing_correlation.py — are MRCLAM's bearing errors independent from frame to frame?

Usage: research/mrclam/mrclam_bearing_correlation.py [DATASET_DIR] [--max-lag-s 48] [--fit-max-lag-s 32]

For every landmark sighting of robots 1-5 of an MRCLAM dataset (default as scripts/run-mrclam.sh:
$OMNISLAM_DATASETS/mrclam/MRCLAM_Dataset6), the bearing residual e = measured bearing - bearing
from the Vicon pose (linearly interpolated, truth samples at most 0.1 s apart) to the landmark's
Vicon position; |e| > 0.1 rad is left out (a wrong barcode), and each robot's mean residual (its
camera's yaw offset) is removed. Prints:
  - the RMS of e over all robots;
  - the correlation of two residuals of one robot, by time lag, for the same landmark and for two
    different landmarks (lag 0: the same frame);
  - the least-squares fit rho(lag) = rho0 exp(-lag / tau) to the same-landmark correlations with
    lag below --fit-max-lag-s (each lag bin weighted by its number of pairs), and the covariance
    rho0 * RMS^2 of the correlated part.
A filter that takes the sightings as independent counts the same information several times when
the correlation is high. Standard library only; read-only on the dataset. Figures quoted in
research/mrclam-diagnosis.md.
"""
import argparse
import bisect
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mrclam_odometry_heading import add_dataset_argument, load, wrap  # noqa: E402  (same folder)

LAG_EDGES_S = [0.0, 0.01, 0.35, 0.7, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0]


def residuals(dataset, robot, subject_of_barcode, landmarks):
    gt = load(os.path.join(dataset, f'Robot{robot}_Groundtruth.dat'))
    gt_t = [g[0] for g in gt]
    out = []
    sightings = load(os.path.join(dataset, f'Robot{robot}_Measurement.dat'), columns=4, merge_equal_times=False)
    for t, barcode, _range, bearing in (row[:4] for row in sightings):  # load() keeps extra columns
        subject = subject_of_barcode.get(int(barcode))
        if subject not in landmarks:
            continue  # another robot, or an unknown barcode
        i = bisect.bisect_left(gt_t, t)
        if i <= 0 or i >= len(gt) or gt_t[i] - gt_t[i - 1] > 0.1 + 1e-6:  # 1e-6: samples 0.1 s apart in the file's decimals
            continue
        s = (t - gt_t[i - 1]) / (gt_t[i] - gt_t[i - 1])
        x = gt[i - 1][1] + s * (gt[i][1] - gt[i - 1][1])
        y = gt[i - 1][2] + s * (gt[i][2] - gt[i - 1][2])
        theta = gt[i - 1][3] + s * wrap(gt[i][3] - gt[i - 1][3])
        lx, ly = landmarks[subject]
        e = wrap(bearing - (math.atan2(ly - y, lx - x) - theta))
        if abs(e) <= 0.1:
            out.append((t, subject, e))
    if out:
        mean = sum(e for _, _, e in out) / len(out)
        out = [(t, subject, e - mean) for t, subject, e in out]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    add_dataset_argument(ap)
    ap.add_argument('--max-lag-s', type=float, default=48.0)
    ap.add_argument('--fit-max-lag-s', type=float, default=32.0)
    args = ap.parse_args()
    if not 0 < args.fit_max_lag_s <= args.max_lag_s <= LAG_EDGES_S[-1]:
        sys.exit(f'need 0 < --fit-max-lag-s <= --max-lag-s <= {LAG_EDGES_S[-1]:g}')
    if not os.path.exists(os.path.join(args.dataset, 'Barcodes.dat')):
        sys.exit(f'{args.dataset}: no Barcodes.dat here (is the MRCLAM dataset present?)')
    barcodes = load(os.path.join(args.dataset, 'Barcodes.dat'), columns=2, timed=False)
    subject_of_barcode = {int(row[1]): int(row[0]) for row in barcodes}
    landmarks = {int(r[0]): (r[1], r[2])
                 for r in load(os.path.join(args.dataset, 'Landmark_Groundtruth.dat'), columns=3, timed=False)}

    per_robot = [residuals(args.dataset, r, subject_of_barcode, landmarks) for r in range(1, 6)
                 if os.path.exists(os.path.join(args.dataset, f'Robot{r}_Measurement.dat'))]
    pooled = [e for rows in per_robot for _, _, e in rows]
    if not pooled:
        sys.exit(f'{args.dataset}: no landmark sighting with a truth pose')
    var = sum(e * e for e in pooled) / len(pooled)
    if var == 0.0:
        sys.exit(f'{args.dataset}: every residual is zero after removing each robot\'s mean; no correlation to compute')
    print(f'{len(pooled)} landmark sightings of {len(per_robot)} robots; residual RMS {math.sqrt(var):.4f} rad '
          f'(each robot\'s mean removed)')

    bins = len(LAG_EDGES_S) - 1
    same = [[0, 0.0, 0.0] for _ in range(bins)]  # pairs, sum of products, sum of lags
    other = [[0, 0.0, 0.0] for _ in range(bins)]
    for rows in per_robot:
        for i, (ti, si, ei) in enumerate(rows):
            for tj, sj, ej in rows[i + 1:]:
                lag = tj - ti
                if lag >= args.max_lag_s:
                    break
                k = bisect.bisect_right(LAG_EDGES_S, lag) - 1
                acc = same[k] if si == sj else other[k]
                acc[0] += 1
                acc[1] += ei * ej
                acc[2] += lag
    print('lag [s]        same landmark: pairs  corr | other landmark: pairs  corr')
    points = []
    for k in range(bins):
        if not same[k][0] and not other[k][0]:
            continue
        cs = same[k][1] / same[k][0] / var if same[k][0] else float('nan')
        co = other[k][1] / other[k][0] / var if other[k][0] else float('nan')
        print(f'{LAG_EDGES_S[k]:5.2f}-{LAG_EDGES_S[k + 1]:5.2f}  {same[k][0]:20d} {cs:5.2f} | '
              f'{other[k][0]:21d} {co:5.2f}')
        if same[k][0]:
            points.append((same[k][2] / same[k][0], cs, same[k][0]))

    fit_points = [p for p in points if p[0] < args.fit_max_lag_s]
    if not fit_points:  # an empty sum is 0 for every (rho0, tau): the grid would "fit" nothing
        sys.exit('no same-landmark pair below --fit-max-lag-s')
    best = None
    for rho0 in [x / 100 for x in range(5, 100)]:
        for tau in [x / 2 for x in range(1, 121)]:
            sse = sum(n * (c - rho0 * math.exp(-lag / tau)) ** 2 for lag, c, n in fit_points)
            if best is None or sse < best[0]:
                best = (sse, rho0, tau)
    _, rho0, tau = best
    print(f'fit over lags < {args.fit_max_lag_s:g} s: rho0 {rho0:.2f}, tau {tau:.1f} s; covariance of the '
          f'correlated part {rho0 * var:.2e} rad^2 (sd {math.sqrt(rho0 * var):.4f} rad)')


if __name__ == '__main__':
    main()
