#!/usr/bin/env python3
"""Geometric oracle of global localisation: how far must the robot drive before its true pose is the
only one in the map that explains what it saw? (issue 56; docs/design/global-localisation.md,
"What the geometry allows").

Reads the output folder of `scripts/evaluate-relocalisation.py` (world files, infos, per-world
results; run without --kidnap/--extend). For each world it regenerates the second run's log
(omnislam-gen-world, the evaluation's seed), cuts it at the evaluation's start, and takes, per frame,
the lamps the detector model really detected (GROUND_TRUTH_FEATURE_LABELS) at the true pose. A twin
is a rigid motion T of the plane, at least 1 m or 5 deg from the identity at the cut's first pose,
that maps the lamps of the first frame with two lamps onto two lamps of the map (every pair of map
lamps is tried, so every twin is found). A twin stays consistent while, in every frame so far,
  - every detected lamp, moved by T, lies within --tol-m (horizontal) and --tol-z-m of a map lamp, and
  - the map lamps the twin pose should see (inside the detection range less --margin-m) but that
    were not detected number, summed over the frames, at most --slack more than at the true pose.
The oracle's travel is the true path's length up to the first frame with no consistent twin: no
localiser, however good, can be sure before it. Prints one line per world and a summary against
the localiser's own travel to its first fix (the evaluation's truth-map results).

  python3 research/relocalisation_oracle.py --out /tmp/reloc-new [--worlds halls-13,irregular-44]
      [--bin build/bin] [--travel-m 5] [--camera-z-m 1.8]

The detection range is the 3-D distance `perception_max_range_m` of the world's info from a camera at
--camera-z-m; this ignores the field of view's edge and the lamp's pixel size, so lamps within
--margin-m of the range are neither required nor counted.
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts"))
from lcm_log_filter import events  # noqa: E402
from world_jobs import cut_start  # noqa: E402

FINGERPRINT = 8


def labels_of(data):
    """utime and the detected lamp ids (>= 0) of a feature_labels_t."""
    utime, _seq, _fseq, n = struct.unpack_from(">qqqi", data, FINGERPRINT)
    ids = struct.unpack_from(f">{n}q", data, FINGERPRINT + 28)
    return utime, sorted({i for i in ids if i >= 0})


def cut_window(run2, seed, family, window_s):
    """True poses and per-frame detected lamps of the evaluation's cut (its start formula)."""
    stamps = [t for t, ch, _ in events(run2) if ch == b"OMNI_FEATURES"]
    start = cut_start(stamps, family, seed, window_s)
    end = start + int(window_s * 1e6)
    poses, frames = {}, []
    for t, ch, data in events(run2):
        if not start <= t < end:
            continue
        if ch == b"GROUND_TRUTH_POSE":
            utime, _s, x, y, th = struct.unpack_from(">qqddd", data, FINGERPRINT)
            poses[utime] = (x, y, th)
        elif ch == b"GROUND_TRUTH_FEATURE_LABELS":
            frames.append(labels_of(data))
    return poses, frames


def travel_at_frames(poses, frames):
    """(pose, travel) at each frame, travel along the true path from the cut's first pose."""
    times = sorted(poses)
    out, cum, prev, i = [], 0.0, poses[times[0]], 0
    for utime, _ids in frames:
        while i < len(times) and times[i] <= utime:
            p = poses[times[i]]
            cum += math.hypot(p[0] - prev[0], p[1] - prev[1])
            prev, i = p, i + 1
        out.append((prev, cum))
    return out


def apply(T, x, y):
    c, s = math.cos(T[2]), math.sin(T[2])
    return T[0] + c * x - s * y, T[1] + s * x + c * y


def candidates(lamps, a, b, args):
    """Every rigid motion mapping lamps a, b onto two map lamps of the same spacing and heights."""
    dab = math.hypot(b[0] - a[0], b[1] - a[1])
    ang_ab = math.atan2(b[1] - a[1], b[0] - a[0])
    for c in lamps:
        if abs(c[2] - a[2]) > args.tol_z_m:
            continue
        for d in lamps:
            if d is c or abs(d[2] - b[2]) > args.tol_z_m:
                continue
            if abs(math.hypot(d[0] - c[0], d[1] - c[1]) - dab) > args.tol_m:
                continue
            phi = math.atan2(d[1] - c[1], d[0] - c[0]) - ang_ab
            cs, sn = math.cos(phi), math.sin(phi)
            yield (c[0] - (cs * a[0] - sn * a[1]), c[1] - (sn * a[0] + cs * a[1]), phi)


def far_from_identity(T, pose):
    x, y = apply(T, pose[0], pose[1])
    dth = abs((T[2] + math.pi) % (2 * math.pi) - math.pi)
    return math.hypot(x - pose[0], y - pose[1]) > 1.0 or dth > math.radians(5.0)


def nearest(lamps, x, y, z, args):
    best = None
    for L in lamps:
        if abs(L[2] - z) <= args.tol_z_m and math.hypot(L[0] - x, L[1] - y) <= args.tol_m:
            d = math.hypot(L[0] - x, L[1] - y)
            if best is None or d < best[0]:
                best = (d, L)
    return None if best is None else best[1]


def unseen_expected(lamps, x, y, seen, rng_m, args):
    """Map lamps well inside the detection range of a camera at (x, y) that are not in `seen`."""
    n = 0
    for L in lamps:
        if L[3] in seen:
            continue
        if math.sqrt((L[0] - x) ** 2 + (L[1] - y) ** 2 + (L[2] - args.camera_z_m) ** 2) <= rng_m - args.margin_m:
            n += 1
    return n


def frame_check(T, lamps, by_id, ids, pose, rng_m, args):
    """(explained, unseen expected at the twin) of one frame for twin T; None if a lamp is unexplained."""
    seen = set()
    for i in ids:
        L = by_id[i]
        x, y = apply(T, L[0], L[1])
        m = nearest(lamps, x, y, L[2], args)
        if m is None:
            return None
        seen.add(m[3])
    tx, ty = apply(T, pose[0], pose[1])
    return unseen_expected(lamps, tx, ty, seen, rng_m, args)


def oracle_travel(lamps, frames, at, rng_m, args):
    """Travel of the first frame after which no twin is consistent (inf if one stays), twins left then."""
    by_id = {L[3]: L for L in lamps}
    first = next((k for k, (_u, ids) in enumerate(frames) if len(ids) >= 2), None)
    if first is None:
        return math.inf, 0
    ids0 = frames[first][1]
    a, b = max(((by_id[i], by_id[j]) for i in ids0 for j in ids0 if i < j),
               key=lambda p: math.hypot(p[0][0] - p[1][0], p[0][1] - p[1][1]))
    twins = {T: 0 for T in candidates(lamps, a, b, args) if far_from_identity(T, at[first][0])}
    for k in range(first, len(frames)):
        ids, (pose, travel) = frames[k][1], at[k]
        truth_unseen = unseen_expected(lamps, pose[0], pose[1], set(ids), rng_m, args)
        for T in list(twins):
            u = frame_check(T, lamps, by_id, ids, pose, rng_m, args)
            if u is None:
                del twins[T]
                continue
            twins[T] += u - truth_unseen
            if twins[T] > args.slack:
                del twins[T]
        if not twins:
            return travel, 0
        if travel > args.max_travel_m:
            break
    return math.inf, len(twins)


def one_world(name, args, tmp):
    import yaml
    family, seed = name.rsplit("-", 1)
    seed = int(seed)
    base = os.path.join(args.out, name)
    with open(base + ".info.json") as f:
        info = json.load(f)
    with open(base + ".world.yaml") as f:
        lamps = [(L["x_m"], L["y_m"], L["z_m"], L["id"]) for L in yaml.safe_load(f)["lights"]["list"]]
    run2 = os.path.join(tmp, name + ".run2.lcm")
    if not os.path.exists(run2):
        subprocess.run([os.path.join(args.bin, "omnislam-gen-world"), "--world", base + ".world.yaml", "--seed",
                        str(seed + 100000), "--out-log", run2], check=True, capture_output=True)
    poses, frames = cut_window(run2, seed, family, args.window_s)
    at = travel_at_frames(poses, frames)
    travel, left = oracle_travel(lamps, frames, at, info["perception_max_range_m"], args)
    with open(base + ".json") as f:
        loc = next(r for r in json.load(f) if r["map"] == "truth")
    regular = info.get("lamps_missing") == 0 and info.get("lamps_extra") == 0 and family == "halls"
    return {"world": name, "regular": regular, "oracle_travel_m": travel, "twins_left": left,
            "localiser_travel_m": loc["travel_to_fix_m"] if loc["fix"] else math.inf, "ok": loc["ok"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="an evaluate-relocalisation.py output folder")
    ap.add_argument("--worlds", default="", help="family-seed,... (default: every world of the folder)")
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                                  "build", "bin"))
    ap.add_argument("--window-s", type=float, default=150.0)
    ap.add_argument("--travel-m", type=float, default=5.0, help="the bar's travel")
    ap.add_argument("--max-travel-m", type=float, default=40.0, help="stop looking after this travel")
    ap.add_argument("--tol-m", type=float, default=0.4)
    ap.add_argument("--tol-z-m", type=float, default=0.5)
    ap.add_argument("--margin-m", type=float, default=1.5)
    ap.add_argument("--slack", type=int, default=2)
    ap.add_argument("--camera-z-m", type=float, default=1.8)
    args = ap.parse_args()
    names = args.worlds.split(",") if args.worlds else sorted(
        f[:-len(".info.json")] for f in os.listdir(args.out) if f.endswith(".info.json"))
    rows = []
    with tempfile.TemporaryDirectory(prefix="omnislam-oracle.") as tmp:
        for name in names:
            r = one_world(name, args, tmp)
            rows.append(r)
            os.remove(os.path.join(tmp, name + ".run2.lcm"))
            print(f"{r['world']:>14} regular={int(r['regular'])} oracle={r['oracle_travel_m']:.2f} m "
                  f"(twins left {r['twins_left']}) localiser={r['localiser_travel_m']:.2f} m ok={int(r['ok'])}",
                  flush=True)
    reachable = [r for r in rows if r["oracle_travel_m"] <= args.travel_m]
    print(f"worlds {len(rows)}; the geometry decides within {args.travel_m} m in {len(reachable)}; "
          f"the localiser's truth-map bar met in {sum(r['ok'] for r in reachable)} of those, "
          f"in {sum(r['ok'] for r in rows) - sum(r['ok'] for r in reachable)} of the others")
    return 0


if __name__ == "__main__":
    sys.exit(main())
