#!/usr/bin/env python3
"""mrclam_group_observability.py — what MRCLAM's landmark groups offer an estimator that must find them.

Usage: research/mrclam/mrclam_group_observability.py [DATASET_DIR] [--group-link-m 0.5] [--visit-gap-s 10]
           [--bearing-sigma-deg 1] [--group-extent-m 0.10] [--gate-sigma 3]

MRCLAM's landmarks stand in tight groups. Without barcodes an estimator sees a group, not a
landmark, and has to recognise the group at each visit. For an MRCLAM dataset (default as
scripts/run-mrclam.sh: $OMNISLAM_DATASETS/mrclam/MRCLAM_Dataset6), with the barcodes and the Vicon
truth as oracles, this prints the figures that limit that recognition:
  - the groups: landmarks joined by single linkage within --group-link-m, each group's centre the
    mean of its members; per robot:
  - the sightings: of landmarks, of the other robots (clutter to the estimator), of unknown barcodes;
  - dead reckoning's relative heading error: the commanded heading change (integral of omega) against
    the Vicon one over windows of 10, 30 and 60 s starting every 5 s (1 s grid), median and 90th
    percentile of its magnitude;
  - visits: a group's sightings split where --visit-gap-s passes without one; their number per group,
    and the parallax of each visit (the spread of the directions from the true positions to the
    group's centre over the visit), median over the visits;
  - triangulation from the TRUE poses: in windows of 20 and 40 s starting every half window, each
    group with at least 4 sightings and 5 deg of parallax in the window is the least-squares crossing
    of its rays; median distance to the group's centre. The error of one window's triangulation even
    without any odometry error;
  - detection at group level: frames (distinct measurement times) in which the group's centre is in
    view from the true pose (|azimuth| < 0.5 rad, range 1-6.5 m); P_D = share of them with a sighting
    of a member; a miss run = the in-view frames without one between two frames with one, 90th and
    99th percentile and longest;
  - a --gate-sigma gate from the TRUE poses on each group's centre, with the bearing noise widened by
    the group's extent (variance sigma^2 + (extent / range)^2): the share of landmark sightings
    whose best-fitting group in the gate is their own, of those with no group in the gate, and of the
    other robots' sightings that fall inside some group's gate.
Standard library only; read-only on the dataset. Figures quoted in research/mrclam-diagnosis.md.
"""
import argparse
import bisect
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mrclam_odometry_heading import add_dataset_argument, load, truth_heading, wrap  # noqa: E402  (same folder)
from mrclam_visual_rotation import Integral  # noqa: E402  (same folder)

HEADING_WINDOWS_S = (10, 30, 60)
TRIANGULATION_WINDOWS_S = (20.0, 40.0)
VIEW_HALF_RAD, VIEW_MIN_M, VIEW_MAX_M = 0.5, 1.0, 6.5


def percentile(values, p):
    """The p-th percentile with linear interpolation between order statistics (numpy's default)."""
    if not values:
        return float('nan')
    v = sorted(values)
    pos = p / 100.0 * (len(v) - 1)
    i = int(math.floor(pos))
    return v[i] if i + 1 >= len(v) else v[i] + (pos - i) * (v[i + 1] - v[i])


def share(k, total):
    """k of total in percent; nan when total is 0."""
    return 100.0 * k / total if total else float('nan')


def median(values):
    return percentile(values, 50.0)


def groups_of(landmarks, link_m):
    """Single-linkage groups of {subject: (x, y)}: a list of (sorted subjects, centre)."""
    subjects = sorted(landmarks)
    parent = {s: s for s in subjects}

    def root(s):
        while parent[s] != s:
            s = parent[s]
        return s
    for i, a in enumerate(subjects):
        for b in subjects[i + 1:]:
            if math.dist(landmarks[a], landmarks[b]) <= link_m:
                parent[root(b)] = root(a)
    members = {}
    for s in subjects:
        members.setdefault(root(s), []).append(s)
    out = []
    for group in sorted(members.values()):
        cx = sum(landmarks[s][0] for s in group) / len(group)
        cy = sum(landmarks[s][1] for s in group) / len(group)
        out.append((group, (cx, cy)))
    return out


class Track:
    """Linear interpolation of a timed table's x and y columns (clamped at the ends)."""

    def __init__(self, rows):
        self.t, self.x, self.y = [r[0] for r in rows], [r[1] for r in rows], [r[2] for r in rows]

    def __call__(self, t):
        i = max(1, min(bisect.bisect_left(self.t, t), len(self.t) - 1))
        s = min(max((t - self.t[i - 1]) / (self.t[i] - self.t[i - 1]), 0.0), 1.0)
        return self.x[i - 1] + s * (self.x[i] - self.x[i - 1]), self.y[i - 1] + s * (self.y[i] - self.y[i - 1])


def crossing(rays):
    """Least-squares crossing point of 2D rays (x, y, direction): None if nearly parallel."""
    a11 = a12 = a22 = b1 = b2 = 0.0
    for x, y, d in rays:
        nx, ny = -math.sin(d), math.cos(d)
        a11 += nx * nx
        a12 += nx * ny
        a22 += ny * ny
        k = nx * x + ny * y
        b1 += nx * k
        b2 += ny * k
    det = a11 * a22 - a12 * a12
    smallest = 0.5 * (a11 + a22) - math.sqrt(0.25 * (a11 - a22) ** 2 + a12 * a12)
    if smallest < 1e-3 * len(rays) or abs(det) < 1e-12:
        return None
    return ((a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det)


def spread(directions):
    """max - min of directions [rad] after unwrapping them in order."""
    if not directions:
        return 0.0
    u = [directions[0]]
    for d in directions[1:]:
        u.append(u[-1] + wrap(d - u[-1]))
    return max(u) - min(u)


def robot(dataset, r, groups, group_of_barcode, robot_barcodes, args):
    odo = load(os.path.join(dataset, f'Robot{r}_Odometry.dat'))
    gt = load(os.path.join(dataset, f'Robot{r}_Groundtruth.dat'), columns=4)
    rows = load(os.path.join(dataset, f'Robot{r}_Measurement.dat'), columns=4, merge_equal_times=False)
    heading = truth_heading(gt)
    position = Track(gt)

    # Sightings, and the true pose at each frame (distinct sighting time), interpolated once.
    sightings = [(row[0], int(row[1]), row[3]) for row in rows]
    pose = {}
    for t, _, _ in sightings:
        if t not in pose:
            pose[t] = position(t) + (heading(t),)
    n_landmark = sum(1 for _, b, _ in sightings if b in group_of_barcode)
    n_robot = sum(1 for _, b, _ in sightings if b in robot_barcodes)
    n = len(sightings)
    print(f'robot {r}: {n} sightings: landmarks {n_landmark} ({share(n_landmark, n):.0f} %), other robots {n_robot} '
          f'({share(n_robot, n):.0f} %), unknown barcodes {n - n_landmark - n_robot}')

    # Dead reckoning's relative heading error.
    commanded = Integral(odo, lambda row: row[2])
    start, end = max(odo[0][0], gt[0][0]) + 1.0, min(odo[-1][0], gt[-1][0]) - 1.0
    grid = [start + k for k in range(int(math.ceil(end - start)))]
    parts = []
    for w in HEADING_WINDOWS_S:
        errors = []
        for i in range(0, len(grid) - w, 5):
            turned = commanded(grid[i + w]) - commanded(grid[i])
            errors.append(abs(wrap(turned - (heading(grid[i + w]) - heading(grid[i])))))
        parts.append(f'{w} s median {math.degrees(median(errors)):.1f} / '
                     f'p90 {math.degrees(percentile(errors, 90)):.1f} deg')
    print('  dead reckoning heading error: ' + ', '.join(parts))

    # Visits and their parallax.
    per_group = [[t for t, b, _ in sightings if group_of_barcode.get(b) == g] for g in range(len(groups))]
    visit_counts, parallaxes = [], []
    for g, seen in enumerate(per_group):
        visits = []
        for t in seen:
            if not visits or t - visits[-1][-1] > args.visit_gap_s:
                visits.append([])
            visits[-1].append(t)
        visit_counts.append(len(visits))
        cx, cy = groups[g][1]
        for times in visits:
            parallaxes.append(spread([math.atan2(cy - pose[t][1], cx - pose[t][0]) for t in times]))
    print(f'  visits (gap {args.visit_gap_s:g} s): {sum(visit_counts)}, per group '
          + ' '.join(str(c) for c in visit_counts)
          + f'; parallax per visit median {math.degrees(median(parallaxes)):.1f} deg')

    # Triangulation of a window from the true poses.
    parts = []
    landmark_sightings = [(t, b, z) for t, b, z in sightings if b in group_of_barcode]
    for w in TRIANGULATION_WINDOWS_S:
        errors = []
        ws = gt[0][0] + 2.0
        while ws < gt[-1][0] - w:
            for g in range(len(groups)):
                rays = []
                for t, b, z in landmark_sightings:
                    if ws <= t < ws + w and group_of_barcode[b] == g:
                        x, y, th = pose[t]
                        rays.append((x, y, th + z))
                if len(rays) < 4:
                    continue
                cx, cy = groups[g][1]
                if spread([math.atan2(cy - y, cx - x) for x, y, _ in rays]) < math.radians(5.0):
                    continue
                p = crossing(rays)
                if p is not None:
                    errors.append(math.dist(p, (cx, cy)))
            ws += w / 2.0
        parts.append(f'{w:g} s windows {len(errors)}, median error {median(errors):.2f} m')
    print('  triangulated from the true poses: ' + '; '.join(parts))

    # Detection at group level, in view of the true pose.
    frames = {}
    for t, b, _ in sightings:
        frames.setdefault(t, set())
        if b in group_of_barcode:
            frames[t].add(group_of_barcode[b])
    in_view = detected = 0
    runs = []
    for g, (_, (cx, cy)) in enumerate(groups):
        run = 0
        for t in sorted(frames):
            x, y, th = pose[t]
            rng = math.hypot(cx - x, cy - y)
            visible = abs(wrap(math.atan2(cy - y, cx - x) - th)) < VIEW_HALF_RAD and VIEW_MIN_M < rng < VIEW_MAX_M
            seen = g in frames[t]
            if visible:
                in_view += 1
                detected += seen
                if not seen:
                    run += 1
            if seen:
                if run:
                    runs.append(run)
                run = 0
    pd = detected / in_view if in_view else float('nan')
    print(f'  detection in view: P_D {pd:.2f} over {in_view} group-frames; miss runs {len(runs)}, '
          f'p90 {percentile(runs, 90):.0f}, p99 {percentile(runs, 99):.0f}, longest {max(runs, default=0)} frames')

    # The gate from the true poses.
    sigma2 = math.radians(args.bearing_sigma_deg) ** 2
    own = none = 0
    robots_in_gate = 0
    for t, b, z in sightings:
        if b not in group_of_barcode and b not in robot_barcodes:
            continue
        x, y, th = pose[t]
        best, best_e = None, None
        for g, (_, (cx, cy)) in enumerate(groups):
            rng = max(math.hypot(cx - x, cy - y), 1e-6)
            e = abs(wrap(math.atan2(cy - y, cx - x) - th - z)) / math.sqrt(sigma2 + (args.group_extent_m / rng) ** 2)
            if e <= args.gate_sigma and (best_e is None or e < best_e):
                best, best_e = g, e
        if b in group_of_barcode:
            own += best == group_of_barcode[b]
            none += best is None
        else:
            robots_in_gate += best is not None
    print(f'  {args.gate_sigma:g}-sigma gate from the true poses: landmark sightings to their own group '
          f'{share(own, n_landmark):.1f} %, to none {share(none, n_landmark):.1f} %; '
          f'other robots\' sightings inside a gate {share(robots_in_gate, n_robot):.1f} %')


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    add_dataset_argument(ap)
    ap.add_argument('--group-link-m', type=float, default=0.5)
    ap.add_argument('--visit-gap-s', type=float, default=10.0)
    ap.add_argument('--bearing-sigma-deg', type=float, default=1.0)
    ap.add_argument('--group-extent-m', type=float, default=0.10)
    ap.add_argument('--gate-sigma', type=float, default=3.0)
    args = ap.parse_args()
    for name in ('group_link_m', 'visit_gap_s', 'bearing_sigma_deg', 'gate_sigma'):
        if not getattr(args, name) > 0:
            sys.exit(f'--{name.replace("_", "-")} must be > 0')
    if not args.group_extent_m >= 0:
        sys.exit('--group-extent-m must be >= 0')
    if not os.path.exists(os.path.join(args.dataset, 'Barcodes.dat')):
        sys.exit(f'{args.dataset}: no Barcodes.dat here (is the MRCLAM dataset present?)')
    barcode_of = {int(row[0]): int(row[1])
                  for row in load(os.path.join(args.dataset, 'Barcodes.dat'), columns=2, timed=False)}
    landmarks = {int(row[0]): (row[1], row[2])
                 for row in load(os.path.join(args.dataset, 'Landmark_Groundtruth.dat'), columns=3, timed=False)}
    groups = groups_of(landmarks, args.group_link_m)
    group_of_barcode = {barcode_of[s]: g for g, (members, _) in enumerate(groups) for s in members if s in barcode_of}
    print(f'{len(landmarks)} landmarks in {len(groups)} groups (link {args.group_link_m:g} m): '
          + '; '.join(f'{g + 1}: ' + ','.join(str(s) for s in members) + f' at ({c[0]:.2f}, {c[1]:.2f})'
                      for g, (members, c) in enumerate(groups)))
    found = 0
    for r in range(1, 6):
        if os.path.exists(os.path.join(args.dataset, f'Robot{r}_Measurement.dat')):
            found += 1
            robot_barcodes = {barcode_of[s] for s in range(1, 6) if s != r and s in barcode_of}
            robot(args.dataset, r, groups, group_of_barcode, robot_barcodes, args)
    if not found:
        sys.exit(f'{args.dataset}: no Robot1..5_Measurement.dat here (is the MRCLAM dataset present?)')


if __name__ == '__main__':
    main()
