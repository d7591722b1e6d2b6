#!/usr/bin/env python3
"""mrclam_visual_rotation.py — how much heading could a visual rotation measurement recover on MRCLAM?

Usage: research/mrclam/mrclam_visual_rotation.py [DATASET_DIR] [--max-gap-s 0.6] [--bearing-sigma-rad 0.0175]

A landmark seen in two consecutive frames measures the rotation between them without a map: its
bearing changes by minus the turn, plus a parallax term that is small over one frame gap. For each
robot of an MRCLAM dataset (default as scripts/run-mrclam.sh: $OMNISLAM_DATASETS/mrclam/MRCLAM_Dataset6)
this takes frames (sightings with one time) at most --max-gap-s apart and pairs the sightings of
the same landmark by their barcode: an oracle association, so the figures are an upper bound on
what such a measurement can give. Prints, per robot:
  - over the frame pairs in which the truth turns by at least 0.03 rad: the RMS error of the visual
    rotation (the median over the pair's landmarks of bearing before - bearing after) and of the
    commanded rotation (integral of omega), both against the Vicon turn;
  - the share of the whole commanded turning (sum of |omega| dt) that falls inside a frame pair
    with such a measurement: turning outside every pair cannot be corrected by it;
  - the heading error RMS over windows of 5 s and 30 s, of the commanded heading and of the
    commanded heading corrected at every such pair by the inverse-variance fusion of the two
    rotations. Commanded variance: 0.12^2 rad^2/rad * |turn| + 0.10^2 rad^2/m * distance (the
    motion model of config/slam/mrclam.yaml); visual variance: 2 * bearing sigma^2 (the importer's
    bearing sigma of 1 deg by default).
Standard library only; read-only on the dataset. Figures quoted in research/mrclam-diagnosis.md.
"""
import argparse
import bisect
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mrclam_odometry_heading import add_dataset_argument, load, truth_heading, wrap  # noqa: E402  (same folder)

ROT_VAR_PER_RAD = 0.12 ** 2   # rad^2 per rad of turn, config/slam/mrclam.yaml rot_sigma_per_sqrt_rad
ROT_VAR_PER_M = 0.10 ** 2     # rad^2 per metre, rot_sigma_per_sqrt_m
TURNING_RAD = 0.03            # a frame pair "turns" when the truth turns at least this much
WINDOWS_S = (5.0, 30.0)


class Integral:
    """Piecewise-linear cumulative integral of one column of a timed table, evaluated at any time."""

    def __init__(self, rows, value):
        self.t = [r[0] for r in rows]
        self.acc = [0.0]
        for i in range(1, len(rows)):
            self.acc.append(self.acc[-1] + value(rows[i - 1]) * (rows[i][0] - rows[i - 1][0]))

    def __call__(self, t):
        i = max(1, min(bisect.bisect_left(self.t, t), len(self.t) - 1))
        s = min(max((t - self.t[i - 1]) / (self.t[i] - self.t[i - 1]), 0.0), 1.0)
        return self.acc[i - 1] + s * (self.acc[i] - self.acc[i - 1])


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else float('nan')


def robot(dataset, r, landmarks, max_gap_s, bearing_sigma):
    odo = load(os.path.join(dataset, f'Robot{r}_Odometry.dat'))
    gt = load(os.path.join(dataset, f'Robot{r}_Groundtruth.dat'), columns=4)
    heading, gt_t0, gt_t1 = truth_heading(gt), gt[0][0], gt[-1][0]
    sightings = load(os.path.join(dataset, f'Robot{r}_Measurement.dat'), columns=4, merge_equal_times=False)
    turn = Integral(odo, lambda row: row[2])
    abs_turn = Integral(odo, lambda row: abs(row[2]))
    dist = Integral(odo, lambda row: abs(row[1]))
    frames = []  # [time, {barcode: bearing}]
    for t, barcode, _range, bearing in (row[:4] for row in sightings):
        if int(barcode) not in landmarks:
            continue  # another robot
        if not frames or frames[-1][0] != t:
            frames.append([t, {}])
        frames[-1][1][int(barcode)] = bearing
    err_vis, err_cmd = [], []
    covered_turn = 0.0
    corrections = []  # (time, cumulative heading correction)
    offset = 0.0
    for (ti, fi), (tj, fj) in zip(frames, frames[1:]):
        if tj - ti > max_gap_s or ti < gt_t0 or tj > gt_t1:
            continue
        rotations = sorted(wrap(fi[b] - fj[b]) for b in fj if b in fi)
        if not rotations:
            continue
        d_vis = rotations[len(rotations) // 2]
        d_cmd = turn(tj) - turn(ti)
        d_true = heading(tj) - heading(ti)
        covered_turn += abs_turn(tj) - abs_turn(ti)
        if abs(d_true) >= TURNING_RAD:
            err_vis.append(d_vis - d_true)
            err_cmd.append(d_cmd - d_true)
        var_cmd = ROT_VAR_PER_RAD * abs(d_cmd) + ROT_VAR_PER_M * (dist(tj) - dist(ti)) + 1e-12
        var_vis = 2.0 * bearing_sigma ** 2
        offset += (d_vis * var_cmd + d_cmd * var_vis) / (var_cmd + var_vis) - d_cmd
        corrections.append((tj, offset))
    times = [c[0] for c in corrections]

    def fused(t):
        i = bisect.bisect_right(times, t)
        return turn(t) + (corrections[i - 1][1] if i else 0.0)

    t0, t1 = max(odo[0][0], gt_t0), min(odo[-1][0], gt_t1)
    total_turn = abs_turn(t1) - abs_turn(t0)
    parts = [f'robot {r}: {len(err_vis)} turning frame pairs, rotation error RMS visual {rms(err_vis):.4f} rad, '
             f'commanded {rms(err_cmd):.4f} rad; {100 * covered_turn / max(total_turn, 1e-12):.0f} % of the '
             f'turning inside a measured pair']
    for w in WINDOWS_S:
        e_cmd, e_fused = [], []
        t = t0
        while t + w <= t1:
            d_true = heading(t + w) - heading(t)
            e_cmd.append(d_true - (turn(t + w) - turn(t)))
            e_fused.append(d_true - (fused(t + w) - fused(t)))
            t += w
        parts.append(f'{w:g} s windows: heading error RMS commanded {rms(e_cmd):.3f}, fused {rms(e_fused):.3f} rad')
    print(parts[0])
    print('  ' + '; '.join(parts[1:]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    add_dataset_argument(ap)
    ap.add_argument('--max-gap-s', type=float, default=0.6)
    ap.add_argument('--bearing-sigma-rad', type=float, default=0.0175)
    args = ap.parse_args()
    if not (args.max_gap_s > 0 and args.bearing_sigma_rad > 0):
        sys.exit('--max-gap-s and --bearing-sigma-rad must be > 0')
    if not os.path.exists(os.path.join(args.dataset, 'Barcodes.dat')):
        sys.exit(f'{args.dataset}: no Barcodes.dat here (is the MRCLAM dataset present?)')
    subjects = {int(row[0]): int(row[1])
                for row in load(os.path.join(args.dataset, 'Barcodes.dat'), columns=2, timed=False)}
    landmark_ids = {int(r[0]) for r in load(os.path.join(args.dataset, 'Landmark_Groundtruth.dat'), columns=3,
                                            timed=False)}
    landmarks = {subjects[s] for s in landmark_ids if s in subjects}  # their barcodes
    found = 0
    for r in range(1, 6):
        if os.path.exists(os.path.join(args.dataset, f'Robot{r}_Measurement.dat')):
            found += 1
            robot(args.dataset, r, landmarks, args.max_gap_s, args.bearing_sigma_rad)
    if not found:
        sys.exit(f'{args.dataset}: no Robot1..5_Measurement.dat here (is the MRCLAM dataset present?)')


if __name__ == '__main__':
    main()
