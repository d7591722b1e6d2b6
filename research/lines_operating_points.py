#!/usr/bin/env python3
# Operating points of the vertical-line detector on the labelled real catadioptric images: reads the
# "line IMAGE real|false AZ length_px L strength S" rows that research_lines_acceptance
# (research/lines_acceptance.cpp) prints, and reports (a) the "oracle" recall, i.e. real lines per image if every unlabelled line were
# removed, and (b) the cut on length and strength that keeps >= 90 % real lines with the most real
# lines in the worst image. Not a product tool: evidence for docs/design/detectors.md (issue 46).
#   build-r/bin/research_lines_acceptance | python3 research/lines_operating_points.py
import collections
import sys

rows = []
for text in sys.stdin:
    f = text.split()
    if len(f) == 8 and f[0] == "line":
        rows.append((int(f[1]), f[2] == "real", float(f[5]), float(f[7])))
if not rows:
    sys.exit("no 'line' rows on stdin (pipe research_lines_acceptance into it)")
images = sorted({r[0] for r in rows})
real = collections.Counter(r[0] for r in rows if r[1])
n_real = sum(real.values())
print(f"lines {len(rows)}, real {n_real} ({100.0 * n_real / len(rows):.1f} %)")
print("oracle (every unlabelled line removed): real per image", [real.get(i, 0) for i in images])
best = None
for min_len in range(38, 200, 2):
    for min_str in range(0, 600, 10):
        kept = [r for r in rows if r[2] >= min_len and r[3] >= min_str]
        k_real = [r for r in kept if r[1]]
        if not kept or len(k_real) < 0.9 * len(kept):
            continue
        per = collections.Counter(r[0] for r in k_real)
        worst = min(per.get(i, 0) for i in images)
        if best is None or (worst, len(k_real)) > (best[0], best[1]):
            best = (worst, len(k_real), len(kept), min_len, min_str, [per.get(i, 0) for i in images])
if best is None:
    print("no cut on length and strength keeps >= 90 % real lines")
else:
    w, kr, k, L, S, per = best
    print(f"best cut with >= 90 % real: length >= {L} px, strength >= {S}: {kr} of {k} real "
          f"({100.0 * kr / k:.1f} %), real per image {per} (worst {w})")
