#!/usr/bin/env python3
"""mrclam_odometry_heading.py — how much of MRCLAM's odometry heading error is systematic.

Usage: research/mrclam/mrclam_odometry_heading.py [DATASET_DIR] [--window-s 5] [--block-s 150]

For each robot of an MRCLAM dataset (default, as scripts/run-mrclam.sh:
$OMNISLAM_DATASETS/mrclam/MRCLAM_Dataset6, $OMNISLAM_DATASETS defaulting to ../shared/datasets), cuts the
run into windows of --window-s seconds and compares the heading change the odometry file commands
(integral of omega) with the heading change of the Vicon truth (unwrapped, linearly interpolated).
Prints, per robot:
  - a least-squares fit of the window's heading error e [rad] = a * distance [m] + b * commanded
    turn [rad] (a: heading drift per metre, b: turn-scale error) over the whole run, with the RMS of
    e before and after removing that fit: if the systematic part were large, an odometry calibration
    (fixed or estimated online) would shrink the error;
  - the same fit over consecutive blocks of --block-s seconds, to see whether a and b are stable;
  - the RMS of e split by what the robot did in the window (straight: summed |omega| dt < 0.05 rad;
    spinning in place: distance < 0.05 m; turning: the rest; windows standing still left out).
Standard library only; read-only on the dataset. Figures quoted in docs/results/mrclam.md.
"""
import argparse
import bisect
import math
import os
import sys


def load(path, columns=3, timed=True, merge_equal_times=True):
    """The numeric rows of an MRCLAM text file (comment and blank lines skipped; exits naming file and
    line on a bad one). With `timed`, column 0 is a time that must not decrease; with
    `merge_equal_times` a repeated time keeps its last line (as the importer's --duplicate-times
    keep-last), otherwise every line is kept (a measurement file has several per frame)."""
    rows = []
    duplicates = 0
    try:
        with open(path) as f:
            for number, line in enumerate(f, 1):
                if line.startswith('#') or not line.strip():
                    continue
                try:
                    row = [float(x) for x in line.split()]
                except ValueError:
                    sys.exit(f'{path}:{number}: a field is not a number')
                if len(row) < columns or not all(math.isfinite(x) for x in row):
                    sys.exit(f'{path}:{number}: expected at least {columns} finite numbers')
                if timed and rows and row[0] < rows[-1][0]:
                    sys.exit(f'{path}:{number}: time {row[0]} before the previous line')
                if timed and merge_equal_times and rows and row[0] == rows[-1][0]:
                    rows[-1] = row
                    duplicates += 1
                else:
                    rows.append(row)
    except OSError as err:
        sys.exit(f'{path}: {err.strerror}')
    if duplicates:
        print(f'{path}: {duplicates} repeated times, the last line of each kept', file=sys.stderr)
    if not rows:
        sys.exit(f'{path}: no data lines')
    return rows


def add_dataset_argument(parser):
    """The optional DATASET_DIR positional of the MRCLAM scripts, defaulting as scripts/run-mrclam.sh
    does: $OMNISLAM_DATASETS/mrclam/MRCLAM_Dataset6, $OMNISLAM_DATASETS defaulting to ../shared/datasets."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    datasets = os.environ.get('OMNISLAM_DATASETS') or os.path.join(root, '..', 'shared', 'datasets')
    parser.add_argument('dataset', nargs='?', default=os.path.join(datasets, 'mrclam', 'MRCLAM_Dataset6'))


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def fit(rows):
    """Least squares e = a*d + b*turn; returns (a, b, rms before, rms after)."""
    sdd = sum(r['d'] ** 2 for r in rows)
    sdc = sum(r['d'] * r['turn'] for r in rows)
    scc = sum(r['turn'] ** 2 for r in rows)
    sde = sum(r['d'] * r['e'] for r in rows)
    sce = sum(r['turn'] * r['e'] for r in rows)
    det = sdd * scc - sdc * sdc
    if abs(det) < 1e-12:
        return float('nan'), float('nan'), float('nan'), float('nan')
    a = (sde * scc - sce * sdc) / det
    b = (sdd * sce - sdc * sde) / det
    n = len(rows)
    rms0 = math.sqrt(sum(r['e'] ** 2 for r in rows) / n)
    rms1 = math.sqrt(sum((r['e'] - a * r['d'] - b * r['turn']) ** 2 for r in rows) / n)
    return a, b, rms0, rms1


def truth_heading(gt):
    """The Vicon heading of ground-truth rows (time, x, y, theta), unwrapped, as a function of time
    (linear between samples, extrapolated from the first or last two outside them)."""
    gt_t = [g[0] for g in gt]
    heading = [gt[0][3]]
    for i in range(1, len(gt)):
        heading.append(heading[-1] + wrap(gt[i][3] - gt[i - 1][3]))

    def heading_at(t):
        i = max(1, min(bisect.bisect_left(gt_t, t), len(gt_t) - 1))
        s = (t - gt_t[i - 1]) / (gt_t[i] - gt_t[i - 1])
        return heading[i - 1] + s * (heading[i] - heading[i - 1])
    return heading_at


def windows(odo, gt, window_s):
    gt_t = [g[0] for g in gt]
    heading_at = truth_heading(gt)
    t0 = odo[0][0]
    sums = {}
    for i in range(len(odo) - 1):
        t, v, w = odo[i][:3]
        dt = odo[i + 1][0] - t
        acc = sums.setdefault(int((t - t0) // window_s), [0.0, 0.0, 0.0])
        acc[0] += abs(v) * dt
        acc[1] += w * dt
        acc[2] += abs(w) * dt
    out = []
    for k, (d, turn, abs_turn) in sorted(sums.items()):
        ts, te = t0 + k * window_s, t0 + (k + 1) * window_s
        if ts < gt_t[0] or te > gt_t[-1] or te > odo[-1][0]:
            continue
        e = (heading_at(te) - heading_at(ts)) - turn
        out.append({'t': ts - t0, 'd': d, 'turn': turn, 'abs_turn': abs_turn, 'e': e})
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    add_dataset_argument(ap)
    ap.add_argument('--window-s', type=float, default=5.0)
    ap.add_argument('--block-s', type=float, default=150.0)
    args = ap.parse_args()
    if args.window_s <= 0 or args.block_s < args.window_s:
        sys.exit('--window-s must be > 0 and --block-s >= --window-s')
    found = 0
    for r in range(1, 6):
        odo_path = os.path.join(args.dataset, f'Robot{r}_Odometry.dat')
        gt_path = os.path.join(args.dataset, f'Robot{r}_Groundtruth.dat')
        if not os.path.exists(odo_path):
            continue
        found += 1
        rows = windows(load(odo_path), load(gt_path), args.window_s)
        if not rows:
            print(f'robot {r}: no window of {args.window_s:g} s inside the truth')
            continue
        a, b, rms0, rms1 = fit(rows)
        print(f'robot {r}: {len(rows)} windows of {args.window_s:g} s; drift {a:+.3f} rad/m, '
              f'turn scale {b:+.3f}; heading error RMS {rms0:.3f} rad, {rms1:.3f} after the fit')
        blocks = []
        for j in range(int(rows[-1]['t'] // args.block_s) + 1):
            sel = [x for x in rows if j * args.block_s <= x['t'] < (j + 1) * args.block_s]
            if len(sel) >= 5:
                ba, bb, _, _ = fit(sel)
                blocks.append(f'{ba:+.3f}/{bb:+.3f}')
        print(f'  per {args.block_s:g} s block (drift/turn scale): ' + ' '.join(blocks))
        kinds = {'straight': [], 'turning': [], 'spinning': []}
        for x in rows:
            if x['d'] < 0.02 and x['abs_turn'] < 0.02:
                continue  # standing still
            kind = ('straight' if x['abs_turn'] < 0.05 else
                    'spinning' if x['d'] < 0.05 else 'turning')
            kinds[kind].append(x)
        parts = []
        for kind, sel in kinds.items():
            if sel:
                rms = math.sqrt(sum(x['e'] ** 2 for x in sel) / len(sel))
                mean_turn = sum(x['abs_turn'] for x in sel) / len(sel)
                parts.append(f'{kind} {len(sel)}: RMS {rms:.3f} rad (mean |turn| {mean_turn:.2f} rad)')
        print('  ' + '; '.join(parts))
    if not found:
        sys.exit(f'{args.dataset}: no Robot1..5_Odometry.dat here (is the MRCLAM dataset present?)')


if __name__ == '__main__':
    main()
