#!/usr/bin/env python3
"""Global localisation on generated worlds (issue 56; docs/design/global-localisation.md, "Evaluation").

For each world (omnislam-gen-world, families halls and irregular): one run maps it (omnislam-slam
--replay of its feature log from the known start pose, --save-map); a second run of the same world
with new odometry and detector noise (--odometry-seed, --detector-seed) is cut to start at a random
time of the drive, i.e. a random place and heading on its path, and replayed with
`start_pose.source: unknown`, the saved map and --localise, and again with a map of the world's
true lamps with 3 cm of noise (--maps: the localiser without the first run's map errors). Scored from the SLAM_LOCALISATION and
GROUND_TRUTH_POSE of its output: localised within 0.3 m / 2 deg after <= 5 m of travel (the issue's
bar), wrong poses reported as localised (> 1 m or > 5 deg off), travel to the first fix, and the
SLAM_POSE error after it. Prints a table (Markdown) and writes OUT/relocalisation.json.

With --kidnap (lost and found, issue 56 item 3): instead of the cut run, the second run starts at
the world's known start pose and is kidnapped once (omnislam-gen-world --kidnap-at-s T --kidnap-to-s
T2: at a random time T it is carried to where the drive is at a random other time T2, at least 30 s
of drive away; the odometry does not see it), replayed in localisation mode with lost.policy
relocalise. Scored: LOST reported after the kidnap (and never before), localised again within 5 m of
travel after the kidnap at 0.3 m / 2 deg, wrong poses reported as localised, SLAM_MAP unchanged (every
message the same landmark bytes), the largest SLAM_POSE error after the new fix. Writes
OUT/kidnap.json.

With --extend (sessions, issue 56 item 4): the first run's first half (the feature log cut at half the
drive's time) is mapped and saved; the second run (new noise, the whole drive) starts with
`start_pose.source: unknown` in that map and extends it (SLAM with the loaded map, not --localise) and
saves it. Scored against the world's lamps (each landmark's distance to the nearest true lamp): the
fix as above, the half map's landmarks before and after (refined: the same ids), the landmarks the
second session added, and the map of one session over the whole drive (the first run's) beside it.
Writes OUT/extend.json.

  python3 scripts/evaluate-relocalisation.py [--families halls,irregular] [--worlds 10] [--first-seed 1]
                                             [--window-s 150] [--maps slam,truth] [--jobs 2] [--out DIR]
                                             [--kidnap | --extend]

Needs omnislam-gen-world, omnislam-slam and omnislam-eval (scripts/build.sh, or OMNISLAM_BUILD_DIR). Deterministic:
the same arguments give the same figures (the cut time comes from a generator seeded by the world's
seed; every program is seeded).
"""
import argparse
import json
import math
import os
import random
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from lcm_log_filter import HEADER, SYNC, events  # noqa: E402
from world_jobs import cut_start, quantile, run, run_worlds, truth_lamps  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(os.environ.get("OMNISLAM_BUILD_DIR", os.path.join(ROOT, "build")), "bin")
CONFIG = os.path.join(ROOT, "config", "slam", "sports_hall.yaml")
FINGERPRINT = 8  # every LCM message starts with its type's 8-byte hash


def pose_of(data):
    """utime, x, y, theta of a pose_t (lcmtypes/pose_t.lcm: utime, seq, x_m, y_m, theta_rad, ...)."""
    utime, _seq, x, y, th = struct.unpack_from(">qqddd", data, FINGERPRINT)
    return utime, x, y, th


def localisation_of(data):
    """utime, state, num_hypotheses, num_reported and hypothesis 0 (x, y, theta) of a slam_localisation_t."""
    p = FINGERPRINT
    utime, _seq, _iseq = struct.unpack_from(">qqq", data, p)
    p += 24
    (state,) = struct.unpack_from(">b", data, p)
    p += 1
    nh, _nt, _nf, nr = struct.unpack_from(">iiii", data, p)
    p += 16
    best = None
    if nr > 0:
        x = struct.unpack_from(">d", data, p)[0]
        y = struct.unpack_from(">d", data, p + 8 * nr)[0]
        th = struct.unpack_from(">d", data, p + 16 * nr)[0]
        best = (x, y, th)
    return utime, state, nh, best


def cut_log(src, dst, start_us, end_us):
    """The events of src with log time in [start_us, end_us), renumbered."""
    n = 0
    with open(dst, "wb") as out:
        for utime, channel, data in events(src):
            if start_us <= utime < end_us:
                out.write(HEADER.pack(SYNC, n, utime, len(channel), len(data)) + channel + data)
                n += 1
    return n


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def score(out_log):
    """The run's figures from its output log."""
    truth, loc, slam = [], [], []
    for _t, channel, data in events(out_log):
        if channel == b"GROUND_TRUTH_POSE":
            truth.append(pose_of(data))
        elif channel == b"SLAM_LOCALISATION":
            loc.append(localisation_of(data))
        elif channel == b"SLAM_POSE":
            slam.append(pose_of(data))
    truth.sort()
    travel, cum = [0.0], 0.0
    for a, b in zip(truth, truth[1:]):
        cum += math.hypot(b[1] - a[1], b[2] - a[2])
        travel.append(cum)
    times = [t[0] for t in truth]

    def at(utime):  # nearest true pose and the travel up to it
        import bisect
        i = min(max(bisect.bisect_left(times, utime), 0), len(times) - 1)
        if i > 0 and abs(times[i - 1] - utime) < abs(times[i] - utime):
            i -= 1
        return truth[i], travel[i]

    def err(pose, utime):
        t, _ = at(utime)
        return math.hypot(pose[0] - t[1], pose[1] - t[2]), abs(wrap(pose[2] - t[3])) * 180 / math.pi

    r = {"frames_localising": len(loc), "fix": False, "wrong": 0, "travel_to_fix_m": None,
         "fix_error_m": None, "fix_error_deg": None, "last_state": loc[-1][1] if loc else None,
         "max_hypotheses": max((l[2] for l in loc), default=0), "window_travel_m": travel[-1] if travel else 0.0}
    for utime, state, _nh, best in loc:
        if state != 2 or best is None:
            continue
        e_m, e_deg = err(best, utime)
        if e_m > 1.0 or e_deg > 5.0:
            r["wrong"] += 1
        if not r["fix"]:
            r.update(fix=True, travel_to_fix_m=at(utime)[1], fix_error_m=e_m, fix_error_deg=e_deg)
    errs = [err(p[1:], p[0])[0] for p in slam]
    r["slam_pose_max_error_m"] = max(errs) if errs else None
    r["slam_poses"] = len(errs)
    return r


def score_kidnap(out_log, kidnap_s):
    """The kidnapped run's figures from its output log (kidnap_s: the kidnap's time of the drive)."""
    truth, loc, slam, maps = [], [], [], []
    for _t, channel, data in events(out_log):
        if channel == b"GROUND_TRUTH_POSE":
            truth.append(pose_of(data))
        elif channel == b"SLAM_LOCALISATION":
            loc.append(localisation_of(data))
        elif channel == b"SLAM_POSE":
            slam.append(pose_of(data))
        elif channel == b"SLAM_MAP":
            maps.append(data[FINGERPRINT + 24:])  # the landmarks, without utime, seq, input_seq
    truth.sort()
    kidnap = truth[0][0] + int(kidnap_s * 1e6)
    jump = max((math.hypot(b[1] - a[1], b[2] - a[2]), b[0]) for a, b in zip(truth, truth[1:]))
    cum, travel = 0.0, {}
    for a, b in zip(truth, truth[1:]):  # the path length from the kidnap on, the jump left out
        if b[0] > kidnap:
            cum += math.hypot(b[1] - a[1], b[2] - a[2]) if b[0] != jump[1] else 0.0
        travel[b[0]] = cum
    times = [t[0] for t in truth]

    def at(utime):
        import bisect
        i = min(max(bisect.bisect_left(times, utime), 0), len(times) - 1)
        return truth[i], travel.get(truth[i][0], 0.0)

    def err(pose, utime):
        t, _ = at(utime)
        return math.hypot(pose[0] - t[1], pose[1] - t[2]), abs(wrap(pose[2] - t[3])) * 180 / math.pi

    r = {"carried_m": jump[0], "lost_before_kidnap": sum(1 for l in loc if l[1] == 3 and l[0] < kidnap),
         "lost": False, "travel_to_lost_m": None, "fix": False, "travel_to_fix_m": None, "fix_error_m": None,
         "fix_error_deg": None, "wrong": 0, "losses": sum(1 for l in loc if l[1] == 3),
         "map_unchanged": bool(maps) and all(m == maps[0] for m in maps)}
    for utime, state, _nh, best in loc:
        if state == 3 and utime >= kidnap and not r["lost"]:
            r.update(lost=True, travel_to_lost_m=at(utime)[1], lost_utime=utime)
        if state != 2 or best is None:
            continue
        e_m, e_deg = err(best, utime)
        r["wrong"] += e_m > 1.0 or e_deg > 5.0
        if r["lost"] and not r["fix"]:
            r.update(fix=True, travel_to_fix_m=at(utime)[1], fix_error_m=e_m, fix_error_deg=e_deg, fix_utime=utime)
    after = [err(p[1:], p[0])[0] for p in slam if r["fix"] and p[0] > r["fix_utime"]]
    r["slam_pose_max_error_m"] = max(after) if after else None
    r["ok"] = bool(r["lost"] and r["fix"] and r["travel_to_fix_m"] <= 5.0 and r["fix_error_m"] <= 0.3
                   and r["fix_error_deg"] <= 2.0 and r["lost_before_kidnap"] == 0)
    return r


def truth_map(world_yaml, path, seed):
    """A saved map (version 2) of the world's lamps with N(0, 3 cm) on each coordinate."""
    import yaml
    with open(world_yaml) as f:
        lights = yaml.safe_load(f)["lights"]["list"]
    rng = random.Random(seed)
    lines = ["format: omnislam-map", "version: 2", "utime: 0", f"num_landmarks: {len(lights)}", "landmarks:"]
    for L in lights:
        x, y, z = (L[k] + rng.gauss(0.0, 0.03) for k in ("x_m", "y_m", "z_m"))
        lines.append(f"  - {{id: {L['id']}, kind: point3d, type: 1, counter: 10, position_m: [{x!r}, {y!r}, {z!r}], "
                     "covariance_m2: [0.0009, 0, 0, 0, 0.0009, 0, 0, 0, 0.0009]}")
    lines.append("end: omnislam-map")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def map_run(base, seed, info, perception):
    """The first run: the world mapped from its known start pose; the map saved; its scores."""
    gen, slam = os.path.join(BIN, "omnislam-gen-world"), os.path.join(BIN, "omnislam-slam")
    run([slam, "--replay", base + ".map-run.lcm", "--config", CONFIG, "--seed", str(seed), "--no-progress",
         "--set", f"start_pose.x_m={info['start_x_m']!r}", "--set", f"start_pose.y_m={info['start_y_m']!r}",
         "--set", f"start_pose.theta_deg={info['start_theta_deg']!r}", *perception,
         "--out", base + ".map-out.lcm", "--save-map", base + ".slam-map.yaml"], base + ".map-slam.txt")
    r = subprocess.run([os.path.join(BIN, "omnislam-eval"), "--json", "--no-tum", base + ".map-out.lcm"],
                       capture_output=True, text=True)
    ev = json.loads(r.stdout) if r.returncode == 0 else {}
    # The second run: the same world and drive, new sensor noise.
    run([gen, "--world", base + ".world.yaml", "--seed", str(seed + 100000), "--out-log", base + ".run2.lcm"],
        base + ".gen2.txt")
    return {"map_landmark_mean_err_m": ev.get("landmark_mean_err_m"), "map_ate_rmse_m": ev.get("ate_rmse_m")}


def kidnap_world(family, seed, a, out, base, info, perception, mapped):
    """The kidnapped second run in localisation mode with lost.policy relocalise, in each map."""
    duration = info["duration_s"]
    rng = random.Random(seed * 7919 + len(family) + 56)
    at_s = 30.0 + rng.random() * max(duration - 120.0, 1.0)  # tracked first, and 60 s left after it
    to_s = at_s
    while abs(to_s - at_s) < 30.0:
        to_s = rng.random() * max(duration - 60.0, 1.0)
    run([os.path.join(BIN, "omnislam-gen-world"), "--world", base + ".world.yaml", "--seed", str(seed + 100000),
         "--kidnap-at-s", repr(at_s), "--kidnap-to-s", repr(to_s), "--out-log", base + ".kidnap.lcm"],
        base + ".gen-kidnap.txt")
    results = []
    for kind in a.maps.split(","):
        run([os.path.join(BIN, "omnislam-slam"), "--replay", base + ".kidnap.lcm", "--config", CONFIG, "--seed",
             str(seed), "--no-progress", "--set", f"start_pose.x_m={info['start_x_m']!r}",
             "--set", f"start_pose.y_m={info['start_y_m']!r}", "--set", f"start_pose.theta_deg={info['start_theta_deg']!r}",
             *perception, "--set", "lost.policy=relocalise", "--load-map", base + f".{kind}-map.yaml", "--localise",
             "--out", base + f".kid-{kind}.lcm"], base + f".kid-{kind}.txt")
        r = score_kidnap(base + f".kid-{kind}.lcm", at_s)
        r.update(family=family, seed=seed, map=kind, lamps=info["lamps"], kidnap_at_s=at_s, kidnap_to_s=to_s,
                 lamps_missing=info.get("lamps_missing"), lamps_extra=info.get("lamps_extra"), **mapped)
        results.append(r)
        print(f"evaluate-relocalisation: kidnap {family} {seed} {kind} map: {'ok' if r['ok'] else 'not ok'} "
              f"(carried {r['carried_m']:.1f} m; lost {r['lost']} after {r['travel_to_lost_m']} m; fix {r['fix']} "
              f"after {r['travel_to_fix_m']} m, error {r['fix_error_m']} m {r['fix_error_deg']} deg; "
              f"wrong {r['wrong']}; map unchanged {r['map_unchanged']})", file=sys.stderr)
    return results


def load_map(path):
    """id -> (x, y, z) of a saved map (docs/user/slam-process.md, "Saved maps")."""
    import yaml
    with open(path) as f:
        doc = yaml.safe_load(f)
    return {L["id"]: tuple(L["position_m"]) for L in doc.get("landmarks") or []}


def lamp_errors(landmarks, world_yaml):
    """id -> distance [m] from each landmark to the nearest true lamp of the world."""
    lamps = truth_lamps(world_yaml)
    return {i: min(math.dist(p, q) for q in lamps) for i, p in landmarks.items()}


def extend_world(family, seed, a, base, info, perception, mapped):
    """Sessions: the first half of the first run mapped and saved, the second run extending it."""
    slam = os.path.join(BIN, "omnislam-slam")
    stamps = [t for t, ch, _ in events(base + ".map-run.lcm") if ch == b"OMNI_FEATURES"]
    cut_log(base + ".map-run.lcm", base + ".half.lcm", 0, stamps[0] + (stamps[-1] - stamps[0]) // 2)
    run([slam, "--replay", base + ".half.lcm", "--config", CONFIG, "--seed", str(seed), "--no-progress",
         "--set", f"start_pose.x_m={info['start_x_m']!r}", "--set", f"start_pose.y_m={info['start_y_m']!r}",
         "--set", f"start_pose.theta_deg={info['start_theta_deg']!r}", *perception,
         "--out", base + ".half-out.lcm", "--save-map", base + ".half-map.yaml"], base + ".half-slam.txt")
    run([slam, "--replay", base + ".run2.lcm", "--config", CONFIG, "--seed", str(seed), "--no-progress",
         "--set", "start_pose.source=unknown", *perception, "--load-map", base + ".half-map.yaml",
         "--out", base + ".ext-out.lcm", "--save-map", base + ".ext-map.yaml"], base + ".ext-slam.txt")
    r = score(base + ".ext-out.lcm")
    world = base + ".world.yaml"
    # Never localised (a regular grid): no filter, so no map is saved; the half map stands for it.
    ext_path = base + ".ext-map.yaml" if os.path.exists(base + ".ext-map.yaml") else base + ".half-map.yaml"
    half, ext, whole = (load_map(p) for p in (base + ".half-map.yaml", ext_path, base + ".slam-map.yaml"))
    e_half, e_ext, e_whole = (lamp_errors(m, world) for m in (half, ext, whole))
    old = [i for i in half if i in ext]
    new = [i for i in ext if i not in half]
    mean = lambda v: sum(v) / len(v) if v else None  # noqa: E731
    r.update(family=family, seed=seed, lamps=info["lamps"], half_landmarks=len(half), ext_landmarks=len(ext),
             whole_landmarks=len(whole), old_kept=len(old), added=len(new),
             half_mean_err_m=mean(list(e_half.values())), old_after_mean_err_m=mean([e_ext[i] for i in old]),
             old_before_mean_err_m=mean([e_half[i] for i in old]), added_mean_err_m=mean([e_ext[i] for i in new]),
             ext_mean_err_m=mean(list(e_ext.values())), whole_mean_err_m=mean(list(e_whole.values())),
             old_refined=sum(e_ext[i] < e_half[i] for i in old), **mapped)
    print(f"evaluate-relocalisation: extend {family} {seed}: fix {r['fix']} (wrong {r['wrong']}); half map "
          f"{len(half)} lamps {r['half_mean_err_m']}, extended {len(ext)} ({len(new)} added) {r['ext_mean_err_m']}, "
          f"one whole session {len(whole)} {r['whole_mean_err_m']}", file=sys.stderr)
    return [r]


def one_world(family, seed, a, out):
    base = os.path.join(out, f"{family}-{seed}")
    result_path = base + (".kidnap.json" if a.kidnap else ".extend.json" if a.extend else ".json")
    if os.path.exists(result_path):
        with open(result_path) as f:
            return json.load(f)
    run([os.path.join(BIN, "omnislam-gen-world"), "--family", family, "--seed", str(seed), "--out-world",
         base + ".world.yaml", "--out-log", base + ".map-run.lcm", "--out-info", base + ".info.json"], base + ".gen.txt")
    with open(base + ".info.json") as f:
        info = json.load(f)
    perception = ["--set", f"filter.perception.max_range_m={info['perception_max_range_m']!r}",
                  "--set", f"filter.perception.min_elevation_deg={info['min_elevation_deg']!r}"]
    mapped = map_run(base, seed, info, perception)
    truth_map(base + ".world.yaml", base + ".truth-map.yaml", seed)
    if a.kidnap or a.extend:
        results = (kidnap_world(family, seed, a, out, base, info, perception, mapped) if a.kidnap
                   else extend_world(family, seed, a, base, info, perception, mapped))
        for suffix in (".map-run.lcm", ".map-out.lcm", ".run2.lcm", ".kidnap.lcm", ".kid-slam.lcm", ".kid-truth.lcm",
                       ".half.lcm", ".half-out.lcm", ".ext-out.lcm"):
            if not a.keep_logs and os.path.exists(base + suffix):
                os.remove(base + suffix)
        with open(result_path, "w") as f:
            json.dump(results, f, indent=1)
        return results
    # The second run cut to start at a random time: a random place and heading on the drive.
    stamps = [t for t, ch, _ in events(base + ".run2.lcm") if ch == b"OMNI_FEATURES"]
    start = cut_start(stamps, family, seed, a.window_s)
    cut_log(base + ".run2.lcm", base + ".cut.lcm", start, start + int(a.window_s * 1e6))
    results = []
    for kind in a.maps.split(","):
        run([os.path.join(BIN, "omnislam-slam"), "--replay", base + ".cut.lcm", "--config", CONFIG, "--seed",
             str(seed), "--no-progress", "--set", "start_pose.source=unknown", *perception, "--load-map",
             base + f".{kind}-map.yaml", "--localise", "--out", base + f".loc-{kind}.lcm"], base + f".loc-{kind}.txt")
        r = score(base + f".loc-{kind}.lcm")
        r.update(family=family, seed=seed, map=kind, lamps=info["lamps"], start_offset_s=(start - stamps[0]) * 1e-6,
                 lamps_missing=info.get("lamps_missing"), lamps_extra=info.get("lamps_extra"), **mapped)
        r["ok"] = bool(r["fix"] and r["travel_to_fix_m"] <= 5.0 and r["fix_error_m"] <= 0.3
                       and r["fix_error_deg"] <= 2.0)
        results.append(r)
        print(f"evaluate-relocalisation: {family} {seed} {kind} map: {'ok' if r['ok'] else 'not ok'} "
              f"(fix {r['fix']}, travel {r['travel_to_fix_m']}, error {r['fix_error_m']} m "
              f"{r['fix_error_deg']} deg, wrong {r['wrong']})", file=sys.stderr)
    for suffix in (".map-run.lcm", ".map-out.lcm", ".run2.lcm", ".cut.lcm", ".loc-slam.lcm", ".loc-truth.lcm"):
        if not a.keep_logs and os.path.exists(base + suffix):
            os.remove(base + suffix)
    with open(result_path, "w") as f:
        json.dump(results, f, indent=1)
    return results


def groups(results):
    """(map kind, family, its results) for each map kind x family, and x "all" families."""
    for kind in sorted({r["map"] for r in results}):
        for fam in sorted({r["family"] for r in results}) + ["all"]:
            yield kind, fam, [r for r in results if r["map"] == kind and fam in ("all", r["family"])]


def table(results):
    lines = ["| map | family | worlds | localised <= 5 m, 0.3 m / 2 deg | wrong poses reported localised | "
             "never localised | travel to first fix: median / p90 / max [m] | fix error: median / max [m] | "
             "SLAM_POSE error after fix, max [m] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for kind, fam, rs in groups(results):
        fix_err = [r["fix_error_m"] for r in rs if r["fix"]]
        travel = [r["travel_to_fix_m"] for r in rs if r["fix"]]
        post = [r["slam_pose_max_error_m"] for r in rs if r["slam_pose_max_error_m"] is not None]
        lines.append(f"| {kind} | {fam} | {len(rs)} | {sum(r['ok'] for r in rs)} / {len(rs)} | "
                     f"{sum(r['wrong'] for r in rs)} (in {sum(r['wrong'] > 0 for r in rs)} worlds) | "
                     f"{sum(not r['fix'] for r in rs)} | {quantile(travel, 0.5):.2f} / {quantile(travel, 0.9):.2f} / "
                     f"{max(travel, default=float('nan')):.2f} | {quantile(fix_err, 0.5):.3f} / "
                     f"{max(fix_err, default=float('nan')):.3f} | {max(post, default=float('nan')):.3f} |")
    return "\n".join(lines)


def kidnap_table(results):
    lines = ["| map | family | worlds | lost, then localised <= 5 m, 0.3 m / 2 deg | lost reported after the kidnap | "
             "lost before it | wrong poses reported localised | map unchanged | travel to lost: median / max [m] | "
             "travel to the new fix: median / p90 / max [m] | SLAM_POSE error after it, max [m] |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for kind, fam, rs in groups(results):
        to_lost = [r["travel_to_lost_m"] for r in rs if r["lost"]]
        to_fix = [r["travel_to_fix_m"] for r in rs if r["fix"]]
        post = [r["slam_pose_max_error_m"] for r in rs if r["slam_pose_max_error_m"] is not None]
        lines.append(f"| {kind} | {fam} | {len(rs)} | {sum(r['ok'] for r in rs)} / {len(rs)} | "
                     f"{sum(r['lost'] for r in rs)} | {sum(r['lost_before_kidnap'] > 0 for r in rs)} | "
                     f"{sum(r['wrong'] for r in rs)} (in {sum(r['wrong'] > 0 for r in rs)} worlds) | "
                     f"{sum(r['map_unchanged'] for r in rs)} / {len(rs)} | "
                     f"{quantile(to_lost, 0.5):.2f} / {max(to_lost, default=float('nan')):.2f} | "
                     f"{quantile(to_fix, 0.5):.2f} / {quantile(to_fix, 0.9):.2f} / "
                     f"{max(to_fix, default=float('nan')):.2f} | {max(post, default=float('nan')):.3f} |")
    return "\n".join(lines)


def extend_table(results):
    def fmt(v):
        return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.3f}"

    def med(rs, key):
        return quantile([r[key] for r in rs if r[key] is not None], 0.5) if rs else None

    lines = ["| family | worlds | localised in the half map (wrong) | landmarks: half / extended (added) / one whole "
             "session, medians | half map's landmarks: error before / after, median of means [m]; refined | "
             "added landmarks' error, median of means [m] | whole map's error: extended / one whole session, "
             "median of means [m] | extended no worse than one whole session |",
             "|---|---|---|---|---|---|---|---|"]
    for fam in sorted({r["family"] for r in results}) + ["all"]:
        rs = [r for r in results if fam in ("all", r["family"])]
        fixed = [r for r in rs if r["fix"]]
        no_worse = sum(1 for r in fixed if r["ext_mean_err_m"] is not None and r["whole_mean_err_m"] is not None
                       and r["ext_mean_err_m"] <= r["whole_mean_err_m"])
        lines.append(f"| {fam} | {len(rs)} | {len(fixed)} ({sum(r['wrong'] > 0 for r in rs)}) | "
                     f"{fmt(med(fixed, 'half_landmarks'))} / {fmt(med(fixed, 'ext_landmarks'))} "
                     f"({fmt(med(fixed, 'added'))}) / {fmt(med(fixed, 'whole_landmarks'))} | "
                     f"{fmt(med(fixed, 'old_before_mean_err_m'))} / {fmt(med(fixed, 'old_after_mean_err_m'))}; "
                     f"{sum(r['old_refined'] for r in fixed)} of {sum(r['old_kept'] for r in fixed)} | "
                     f"{fmt(med(fixed, 'added_mean_err_m'))} | {fmt(med(fixed, 'ext_mean_err_m'))} / "
                     f"{fmt(med(fixed, 'whole_mean_err_m'))} | {no_worse} / {len(fixed)} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--families", default="halls,irregular")
    ap.add_argument("--worlds", type=int, default=10, help="worlds per family")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--window-s", type=float, default=150.0, help="length of the second run [s]")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="")
    ap.add_argument("--maps", default="slam,truth",
                    help="the maps localised in: slam (the first run's saved map), truth (the world's lamps with "
                         "3 cm of noise: the localiser alone, without the map's errors)")
    ap.add_argument("--keep-logs", action="store_true")
    ap.add_argument("--kidnap", action="store_true",
                    help="lost and found: the second run starts at the known start and is kidnapped once")
    ap.add_argument("--extend", action="store_true",
                    help="sessions: the second run starts unknown in the first half's map and extends it")
    a = ap.parse_args()
    if a.kidnap and a.extend:
        ap.error("--kidnap and --extend are two evaluations: give one")
    if a.worlds < 1 or a.jobs < 1 or a.first_seed < 1 or a.window_s <= 0:
        ap.error("--worlds, --jobs, --first-seed and --window-s must be positive")
    if not set(a.maps.split(",")) <= {"slam", "truth"}:
        ap.error("--maps takes slam, truth or slam,truth")
    for t in ("omnislam-gen-world", "omnislam-slam", "omnislam-eval"):
        if not os.access(os.path.join(BIN, t), os.X_OK):
            ap.error(f"{BIN}/{t} missing: run scripts/build.sh first")
    out = a.out or tempfile.mkdtemp(prefix="omnislam-reloc.")
    os.makedirs(out, exist_ok=True)
    worlds = [(f, s) for f in a.families.split(",") for s in range(a.first_seed, a.first_seed + a.worlds)]
    per_world, failed = run_worlds(lambda f, s: one_world(f, s, a, out), worlds, a.jobs, "evaluate-relocalisation")
    results = [r for rs in per_world for r in rs]
    name = "kidnap.json" if a.kidnap else "extend.json" if a.extend else "relocalisation.json"
    with open(os.path.join(out, name), "w") as f:
        json.dump({"results": results, "failed": failed}, f, indent=1)
    print(kidnap_table(results) if a.kidnap else extend_table(results) if a.extend else table(results))
    print(f"\nfiles in {out}; {len(failed)} runs failed", file=sys.stderr)
    return 0 if not failed else 1


if __name__ == "__main__":
    sys.exit(main())
