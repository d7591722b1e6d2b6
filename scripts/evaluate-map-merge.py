#!/usr/bin/env python3
"""Merging two sessions' maps on generated worlds (issue 56, item 4; docs/design/global-localisation.md,
"Merging two sessions (item 4)").

For each world (omnislam-gen-world, families halls and irregular): session A maps it (omnislam-slam
--replay of its feature log from the known start pose, --save-map, as scripts/evaluate-relocalisation.py
does); session B maps the same world and drive with new odometry and detector noise (the log of
--seed + 100000, the SLAM's --seed + 100000). B's saved map is moved by a random SE(2) transform M
(x, y in [-50, 50] m, heading in [-180, 180) deg, from a generator seeded by the world's seed): its
frame is unknown to the merge. omnislam-merge-maps A B' --out M merges them. Scored against the
world's true lamps: the landmark errors of A, of B (B' moved back by the true M^-1) and of the merged
map (one-to-one assignment within a 2 m gate, 3D distances, as omnislam-eval's mapErrors: the most
pairs, then the least summed distance), the registration's error (the joint solve's T_AB against
M^-1: the mean distance between B's lamps moved by each, and the heading), and the refused merges. Then pairs of maps of different worlds (A of one world, B' of another,
within and across the families), all of which must be refused.

  python3 scripts/evaluate-map-merge.py [--families halls,irregular] [--worlds 10] [--first-seed 1]
                                        [--pairs-per-world 2] [--jobs 1] [--out DIR] [--merge-flag=--key=value ...]

Needs omnislam-gen-world, omnislam-slam and omnislam-merge-maps (scripts/build.sh, or
OMNISLAM_BUILD_DIR). Deterministic: every program is seeded, M from the world's seed. Prints Markdown
tables and writes OUT/map-merge.json.
"""
import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from world_jobs import quantile, run, run_worlds, truth_lamps  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(os.environ.get("OMNISLAM_BUILD_DIR", os.path.join(ROOT, "build")), "bin")
CONFIG = os.path.join(ROOT, "config", "slam", "sports_hall.yaml")
GATE_M = 2.0  # omnislam-eval's default landmark gate
FORBIDDEN = 1e12


def load_map(path):
    with open(path) as f:
        m = yaml.safe_load(f)
    return m


def move_map(m, pose, path):
    """Writes map m moved by pose (x, y, theta): p' = R p + t, covariances R C R^T, z kept."""
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    R = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    lines = ["format: omnislam-map", "version: 2", f"utime: {m['utime']}", f"num_landmarks: {len(m['landmarks'])}",
             "landmarks:"]
    for lm in m["landmarks"]:
        px, py, pz = lm["position_m"]
        C = [[lm["covariance_m2"][3 * i + j] for j in range(3)] for i in range(3)]
        RC = [[sum(R[i][k] * C[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
        RCR = [[sum(RC[i][k] * R[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
        for i in range(3):  # exactly symmetric, as loadMap checks
            for j in range(i):
                RCR[i][j] = RCR[j][i]
        cov = ", ".join(repr(RCR[i][j]) for i in range(3) for j in range(3))
        lines.append(f"  - {{id: {lm['id']}, kind: {lm['kind']}, type: {lm['type']}, counter: {lm['counter']}, "
                     f"position_m: [{x + c * px - s * py!r}, {y + s * px + c * py!r}, {pz!r}], covariance_m2: [{cov}]}}")
    lines.append("end: omnislam-map")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def inverse(pose):
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    return (-c * x - s * y, s * x - c * y, -th)


def apply(T, p):
    c, s = math.cos(T[2]), math.sin(T[2])
    return (T[0] + c * p[0] - s * p[1], T[1] + s * p[0] + c * p[1])


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def hungarian(cost):
    """Row -> column of the least-cost assignment of a rows x cols matrix, rows <= cols (e-maxx)."""
    n, m = len(cost), len(cost[0])
    u, v, p, way = [0.0] * (n + 1), [0.0] * (m + 1), [0] * (m + 1), [0] * (m + 1)
    for i in range(1, n + 1):
        p[0], j0 = i, 0
        minv, used = [math.inf] * (m + 1), [False] * (m + 1)
        while True:
            used[j0] = True
            i0, delta, j1 = p[j0], math.inf, 0
            for j in range(1, m + 1):
                if not used[j]:
                    cur = cost[i0 - 1][j - 1] - u[i0] - v[j]
                    if cur < minv[j]:
                        minv[j], way[j] = cur, j0
                    if minv[j] < delta:
                        delta, j1 = minv[j], j
            for j in range(m + 1):
                if used[j]:
                    u[p[j]] += delta
                    v[j] -= delta
                else:
                    minv[j] -= delta
            j0 = j1
            if p[j0] == 0:
                break
        while j0:
            j1 = way[j0]
            p[j0] = p[j1]
            j0 = j1
    col = [-1] * n
    for j in range(1, m + 1):
        if p[j]:
            col[p[j] - 1] = j - 1
    return col


def aligned(est, truth):
    """est moved by the rigid 2D transform (closed-form Procrustes) that best fits its lamps matched to
    the truth (map_errors' assignment) onto them: the map's shape, its frame's error left out."""
    pairs = map_errors(est, truth, with_pairs=True)[2]
    if len(pairs) < 2:
        return est
    ma = [sum(truth[j][k] for _, j in pairs) / len(pairs) for k in (0, 1)]
    mb = [sum(est[i][k] for i, _ in pairs) / len(pairs) for k in (0, 1)]
    dot = sum((est[i][0] - mb[0]) * (truth[j][0] - ma[0]) + (est[i][1] - mb[1]) * (truth[j][1] - ma[1]) for i, j in pairs)
    cross = sum((est[i][0] - mb[0]) * (truth[j][1] - ma[1]) - (est[i][1] - mb[1]) * (truth[j][0] - ma[0]) for i, j in pairs)
    th = math.atan2(cross, dot)
    c, s = math.cos(th), math.sin(th)
    return [(ma[0] + c * (x - mb[0]) - s * (y - mb[1]), ma[1] + s * (x - mb[0]) + c * (y - mb[1]), z) for x, y, z in est]


def map_errors(est, truth, with_pairs=False):
    """Per-landmark errors [m] of the one-to-one assignment within GATE_M, and the spurious count."""
    parent = list(range(len(est) + len(truth)))

    def root(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k
    paired = set()
    for i, e in enumerate(est):
        for j, t in enumerate(truth):
            if math.dist(e, t) <= GATE_M:
                paired.update((i, len(est) + j))
                parent[root(i)] = root(len(est) + j)
    groups = {}
    for k in sorted(paired):
        groups.setdefault(root(k), ([], []))[0 if k < len(est) else 1].append(k if k < len(est) else k - len(est))
    errors, pairs = [], []
    for ei, ti in groups.values():
        rows, cols = (ei, ti) if len(ei) <= len(ti) else (ti, ei)
        dist = [[math.dist(est[r], truth[c]) if rows is ei else math.dist(est[c], truth[r]) for c in cols] for r in rows]
        cost = [[d if d <= GATE_M else FORBIDDEN for d in row] for row in dist]
        for r, c in enumerate(hungarian(cost)):
            if c >= 0 and dist[r][c] <= GATE_M:
                errors.append(dist[r][c])
                pairs.append((rows[r], cols[c]) if rows is ei else (cols[c], rows[r]))
    if with_pairs:
        return errors, len(est) - len(errors), pairs
    return errors, len(est) - len(errors)


def summary(errors, spurious):
    return {"mean_m": sum(errors) / len(errors) if errors else None, "median_m": quantile(errors, 0.5) if errors else None,
            "p90_m": quantile(errors, 0.9) if errors else None, "matched": len(errors), "spurious": spurious}


def positions(m):
    return [tuple(lm["position_m"]) for lm in m["landmarks"] if lm["kind"] == "point3d"]


def slam_run(base, log, seed, info, tag):
    perception = ["--set", f"filter.perception.max_range_m={info['perception_max_range_m']!r}",
                  "--set", f"filter.perception.min_elevation_deg={info['min_elevation_deg']!r}"]
    run([os.path.join(BIN, "omnislam-slam"), "--replay", log, "--config", CONFIG, "--seed", str(seed), "--no-progress",
         "--set", f"start_pose.x_m={info['start_x_m']!r}", "--set", f"start_pose.y_m={info['start_y_m']!r}",
         "--set", f"start_pose.theta_deg={info['start_theta_deg']!r}", *perception, "--out", base + f".{tag}-out.lcm",
         "--save-map", base + f".{tag}-map.yaml"], base + f".{tag}-slam.txt")
    os.remove(base + f".{tag}-out.lcm")


def merge(a, path_A, path_B, out, log):
    """omnislam-merge-maps A B --out out: (decision, reason, joint T or None)."""
    argv = [os.path.join(BIN, "omnislam-merge-maps"), path_A, path_B, "--out", out, *a.merge_flag]
    r = subprocess.run(argv, capture_output=True, text=True)
    with open(log, "w") as f:
        f.write(r.stdout + r.stderr)
    if r.returncode not in (0, 3):
        raise RuntimeError(f"omnislam-merge-maps exited {r.returncode}: {r.stderr[-600:]}")
    decision = next((ln.split(": ", 1)[1].split(" (")[0] for ln in r.stdout.splitlines() if ln.startswith("decision: ")),
                    "?")
    T = None
    for ln in r.stdout.splitlines():
        if ln.startswith("joint solve: T_AB = ("):
            x, y, th = (float(v.split()[0]) for v in ln.split("(", 1)[1].split(")")[0].split(", "))
            T = (x, y, math.radians(th))
    return decision, (r.stderr.strip().splitlines() or [""])[-1], T


def session_maps(family, seed, base):
    """The world, and the saved maps of its two sessions (A: the world's seed; B: + 100000)."""
    gen = os.path.join(BIN, "omnislam-gen-world")
    run([gen, "--family", family, "--seed", str(seed), "--out-world", base + ".world.yaml", "--out-log",
         base + ".run-a.lcm", "--out-info", base + ".info.json"], base + ".gen.txt")
    run([gen, "--world", base + ".world.yaml", "--seed", str(seed + 100000), "--out-log", base + ".run-b.lcm"],
        base + ".gen-b.txt")
    with open(base + ".info.json") as f:
        info = json.load(f)
    slam_run(base, base + ".run-a.lcm", seed, info, "a")
    slam_run(base, base + ".run-b.lcm", seed + 100000, info, "b")
    for suffix in (".run-a.lcm", ".run-b.lcm"):
        os.remove(base + suffix)


def one_world(family, seed, a, out):
    base = os.path.join(out, f"{family}-{seed}")
    result_path = base + ".json"
    if os.path.exists(result_path):
        with open(result_path) as f:
            return json.load(f)
    if not all(os.path.exists(base + x) for x in (".world.yaml", ".info.json", ".a-map.yaml", ".b-map.yaml")):
        session_maps(family, seed, base)  # (the maps of an earlier run in OUT are reused: merges redone)
    rng = random.Random(seed * 7919 + len(family) + 4)
    M = (rng.uniform(-50.0, 50.0), rng.uniform(-50.0, 50.0), rng.uniform(-math.pi, math.pi))
    map_B = load_map(base + ".b-map.yaml")
    move_map(map_B, M, base + ".b-moved.yaml")
    truth = truth_lamps(base + ".world.yaml")
    r = {"family": family, "seed": seed, "lamps": len(truth), "moved_by": M}
    decision, reason, T = merge(a, base + ".a-map.yaml", base + ".b-moved.yaml", base + ".merged.yaml",
                                base + ".merge.txt")
    r.update(decision=decision, reason=reason)
    move_map(load_map(base + ".b-moved.yaml"), inverse(M), base + ".b-back.yaml")  # B scored in the world frame
    for tag, path in (("A", base + ".a-map.yaml"), ("B", base + ".b-back.yaml"), ("merged", base + ".merged.yaml")):
        if tag == "merged" and decision != "accepted":
            continue
        est = positions(load_map(path))
        errors, spurious = map_errors(est, truth)
        r[tag], r[tag + "_errors"] = summary(errors, spurious), errors
        errors, spurious = map_errors(aligned(est, truth), truth)
        r[tag + "_aligned"], r[tag + "_aligned_errors"] = summary(errors, spurious), errors
    if T is not None:  # T_AB against M^-1: where it puts B's lamps (not its origin, far from them)
        moved = positions(load_map(base + ".b-moved.yaml"))
        r["T_error_m"] = sum(math.dist(apply(T, p), apply(inverse(M), p)) for p in moved) / max(len(moved), 1)
        r["T_error_deg"] = abs(math.degrees(wrap(T[2] + M[2])))
    print(f"evaluate-map-merge: {family} {seed}: {decision}; mean error A {r['A']['mean_m']}, B {r['B']['mean_m']}, "
          f"merged {r.get('merged', {}).get('mean_m')}; T error {r.get('T_error_m')} m {r.get('T_error_deg')} deg"
          + ("" if decision == "accepted" else f" ({reason})"), file=sys.stderr)
    with open(result_path, "w") as f:
        json.dump(r, f, indent=1)
    return r


def other_world_pairs(worlds, per_world):
    """(A world, B world) pairs of different worlds: within each family (the next per_world worlds)
    and across the families (world i of one with world i of the next)."""
    fams = sorted({f for f, _ in worlds})
    pairs = []
    for f in fams:
        seeds = [s for g, s in worlds if g == f]
        for i, s in enumerate(seeds):
            pairs += [((f, s), (f, seeds[(i + k) % len(seeds)])) for k in range(1, per_world + 1) if len(seeds) > k]
    for f, g in zip(fams, fams[1:] + fams[:1]):
        if f != g:
            pairs += [((f, s), (g, s)) for s in sorted({s for h, s in worlds if h == f} & {s for h, s in worlds if h == g})]
    return pairs


def other_world_merges(a, out, pairs):
    results = []
    for (fa, sa), (fb, sb) in pairs:
        tag = f"{fa}-{sa}.vs.{fb}-{sb}"
        decision, reason, _ = merge(a, os.path.join(out, f"{fa}-{sa}.a-map.yaml"),
                                    os.path.join(out, f"{fb}-{sb}.b-moved.yaml"), os.path.join(out, tag + ".merged.yaml"),
                                    os.path.join(out, tag + ".merge.txt"))
        results.append({"A": f"{fa} {sa}", "B": f"{fb} {sb}", "decision": decision, "reason": reason})
        if decision == "accepted":
            print(f"evaluate-map-merge: WRONG: {tag} merged ({reason})", file=sys.stderr)
    return results


def good_maps(r):
    """Both sessions' maps are maps of the world: >= 90 % of their lamps within the gate of a true lamp."""
    return all(r[t]["spurious"] <= 0.1 * (r[t]["matched"] + r[t]["spurious"]) for t in ("A", "B"))


def fmt(v, d=3):
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.{d}f}"


def error_row(ok, tag, kind):
    """lamps' error mean / median / p90, the worlds' mean error (median), matched / spurious: of map tag."""
    errs = [e for r in ok for e in r.get(tag + kind + "_errors", [])]
    means = [r[tag + kind]["mean_m"] for r in ok]
    matched, spurious = sum(r[tag + kind]["matched"] for r in ok), sum(r[tag + kind]["spurious"] for r in ok)
    return (f"{fmt(sum(errs) / len(errs) if errs else None)} / {fmt(quantile(errs, 0.5) if errs else None)} / "
            f"{fmt(quantile(errs, 0.9) if errs else None)} | {fmt(quantile(means, 0.5) if means else None)} | "
            f"{matched} / {spurious}")


def table(results, kind=""):
    """kind "": errors in the maps' own frames (as omnislam-eval); "_aligned": after each map's best
    rigid fit to the truth (its shape)."""
    lines = ["| family | worlds | merged | refused (reasons) | map | lamps' error mean / median / p90 [m] | "
             "worlds' mean error, median [m] | matched / spurious lamps | merged's mean <= the better session's | "
             "T_AB error (at B's lamps; heading), worlds whose maps are of the world: n: median / max [m], [deg] |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for fam in sorted({r["family"] for r in results}) + ["all"]:
        rs = [r for r in results if fam in ("all", r["family"])]
        ok = [r for r in rs if r["decision"] == "accepted"]  # the merged worlds: the same for the three maps
        reasons = {}
        for r in rs:
            if r["decision"] != "accepted":
                reasons[r["decision"]] = reasons.get(r["decision"], 0) + 1
        better = sum(r["merged" + kind]["mean_m"] <= min(r["A" + kind]["mean_m"], r["B" + kind]["mean_m"]) for r in ok)
        good = [r for r in ok if good_maps(r)]  # T_AB vs M^-1 means something only for maps of the world
        te, td = [r["T_error_m"] for r in good], [r["T_error_deg"] for r in good]
        for k, tag in enumerate(("A", "B", "merged")):
            head = (f"| {fam} | {len(rs)} | {len(ok)} | {len(rs) - len(ok)} "
                    f"({', '.join(f'{n} {d}' for d, n in sorted(reasons.items()))}) " if k == 0 else "| | | | ")
            tail = (f" | {better} / {len(ok)} | {len(good)}: {fmt(quantile(te, 0.5))} / {fmt(max(te, default=None))}, "
                    f"{fmt(quantile(td, 0.5))} / {fmt(max(td, default=None))} |" if k == 0 else " | | |")
            lines.append(head + f"| {tag} | " + error_row(ok, tag, kind) + tail)
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--families", default="halls,irregular")
    ap.add_argument("--worlds", type=int, default=10, help="worlds per family")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--pairs-per-world", type=int, default=2, help="maps of other worlds of its family merged with each A")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default="")
    ap.add_argument("--merge-flag", action="append", default=[], help="a flag for omnislam-merge-maps (--merge-flag=--x=1)")
    a = ap.parse_args()
    if a.worlds < 1 or a.jobs < 1 or a.first_seed < 1 or a.pairs_per_world < 0:
        ap.error("--worlds, --jobs and --first-seed must be positive, --pairs-per-world >= 0")
    for t in ("omnislam-gen-world", "omnislam-slam", "omnislam-merge-maps"):
        if not os.access(os.path.join(BIN, t), os.X_OK):
            ap.error(f"{BIN}/{t} missing: run scripts/build.sh first")
    out = a.out or tempfile.mkdtemp(prefix="omnislam-merge.")
    os.makedirs(out, exist_ok=True)
    worlds = [(f, s) for f in a.families.split(",") for s in range(a.first_seed, a.first_seed + a.worlds)]
    results, failed = run_worlds(lambda f, s: one_world(f, s, a, out), worlds, a.jobs, "evaluate-map-merge")
    done = [(r["family"], r["seed"]) for r in results]
    others = other_world_merges(a, out, other_world_pairs(done, a.pairs_per_world))
    with open(os.path.join(out, "map-merge.json"), "w") as f:
        json.dump({"results": results, "other_worlds": others, "failed": failed}, f, indent=1)
    print("Landmark errors in the maps' own frames (as omnislam-eval):\n")
    print(table(results))
    print("\nLandmark errors after each map's best rigid fit to the truth (its shape):\n")
    print(table(results, "_aligned"))
    wrong = [o for o in others if o["decision"] == "accepted"]
    reasons = {}
    for o in others:
        reasons[o["decision"]] = reasons.get(o["decision"], 0) + 1
    print(f"\nMaps of different worlds: {len(others) - len(wrong)} of {len(others)} refused "
          f"({', '.join(f'{n} {d}' for d, n in sorted(reasons.items()))})")
    print(f"\nfiles in {out}; {len(failed)} worlds failed", file=sys.stderr)
    return 0 if not failed and not wrong else 1


if __name__ == "__main__":
    sys.exit(main())
