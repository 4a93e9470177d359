#!/usr/bin/env python3
"""Measured features of single_tuck across the variants (paper, stabilised, contact).

Usage: /usr/bin/python3 paper_repro/knit/features.py OUT  (OUT = make_figures.sh's folder)
Writes OUT/features.csv. Definitions (points.csv: wale, level, x, y at the end, x0, y0 at rest;
models/knit_loops.hpp): the tuck is at wale 3, course 2 (chart row 3 from the bottom), its
head at level 3; the held loop on its needle is course 1 (lower point level 1, upper level 3).
  held_loop_height_r: y(3,3) - y(3,1) at the end / r (its start is 2h; rest length h).
  held_loop_base_rise_r, tuck_head_rise_r: y - y0 of points (3,1) and (3,3) / r.
  lateral_dx_toward_tuck_r_d<k>: (x - x0) / r of the level-3 points k wales either side of
                      the tuck, signed + toward the tuck, averaged over the two sides.
r = params.loop_radius from summary.json."""
import csv, json, os, sys
out = sys.argv[1]
CHARTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "models", "charts")
rows = []
for variant in ("paper", "stabilised", "contact"):
    d = f"{out}/single_tuck-{variant}"
    s = json.load(open(f"{d}/summary.json"))
    r = s["params"]["loop_radius"]
    P = {(int(p["wale"]), int(p["level"])): p for p in csv.DictReader(open(f"{d}/points.csv"))}
    f = lambda k, key: float(P[k][key])
    row = {"chart": "single_tuck", "variant": variant,
           "held_loop_height_start_r": round((f((3, 3), "y0") - f((3, 1), "y0")) / r, 3),
           "held_loop_height_end_r": round((f((3, 3), "y") - f((3, 1), "y")) / r, 3),
           "held_loop_base_rise_r": round((f((3, 1), "y") - f((3, 1), "y0")) / r, 3),
           "tuck_head_rise_r": round((f((3, 3), "y") - f((3, 3), "y0")) / r, 3)}
    for k in range(1, 5):
        v = []
        for side in (-1, 1):
            key = (3 + side * k, 3)
            if key in P:
                v.append(-side * (f(key, "x") - f(key, "x0")) / r)  # + toward the tuck
        row[f"lateral_dx_toward_tuck_r_d{k}"] = round(sum(v) / len(v), 3)
    rows.append(row)
with open(f"{out}/features.csv", "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=list(rows[0]))
    w.writeheader(); w.writerows(rows)
print(open(f"{out}/features.csv").read())


# Per tuck and miss stitch of the tuck and miss charts (stitch_features.csv). Chart columns are
# wales from the left, rows courses from the bottom (models/knit_loops.hpp). For the stitch at
# wale i, course c:
#   held_loop_height_*_r: the knit loop on needle i below it (the highest knit course c' < c),
#       from its lower point (level c') to its upper point (the next level present in wale i),
#       at rest and at the end / r (cells stacked on one needle share it).
#   tuck_loop_height_*_r (tucks): from the tuck's base B (the lower points of course c at the
#       nearest knit wales either side, interpolated linearly in wale) to its head (that upper
#       point), along y / r.
#   float_depth_*_r (misses): how far course c's centreline passes behind B where it crosses
#       wale i: B.z minus the lowest z of its samples within r of B in x, / r (centerlines.csv
#       at the end, frames/centerlines_000.vtk at rest; + = behind the fabric's face).
def read_chart(path):
    rows = [line.split("#")[0].strip() for line in open(path)]
    rows = [row for row in rows if row]
    return rows[::-1]  # course 0 first


def vtk_centrelines(path):
    """{course: [(x, y, z)]} of a centerlines VTK file (one polyline per course, in order)."""
    lines = open(path).read().split("\n")
    at = next(i for i, l in enumerate(lines) if l.startswith("POINTS"))
    count = int(lines[at].split()[1])
    pts = [tuple(map(float, lines[at + 1 + k].split())) for k in range(count)]
    at = next(i for i, l in enumerate(lines) if l.startswith("LINES"))
    polylines = int(lines[at].split()[1])
    return {c: [pts[int(k)] for k in lines[at + 1 + c].split()[1:]] for c in range(polylines)}


def csv_centrelines(path):
    courses = {}
    for p in csv.DictReader(open(path)):
        courses.setdefault(int(p["course"]), []).append((float(p["x"]), float(p["y"]),
                                                         float(p["z"])))
    return courses


def stitch_rows(chart_name, variant):
    d = f"{out}/{chart_name}-{variant}"
    s = json.load(open(f"{d}/summary.json"))
    r = s["params"]["loop_radius"]
    chart = read_chart(os.path.join(CHARTS, chart_name + ".chart"))
    P = {(int(p["wale"]), int(p["level"])): p for p in csv.DictReader(open(f"{d}/points.csv"))}
    lines = {"rest": vtk_centrelines(f"{d}/frames/centerlines_000.vtk"),
             "end": csv_centrelines(f"{d}/centerlines.csv")}
    axes = {"rest": ("x0", "y0", "z0"), "end": ("x", "y", "z")}
    found = []
    for c, row in enumerate(chart):
        for i, stitch in enumerate(row):
            if stitch not in "TM":
                continue
            below = max(k for k in range(c) if chart[k][i] == "K")
            upper = min(level for (w, level) in P if w == i and level > below)
            left = max(w for w in range(i) if chart[c][w] == "K")
            right = min(w for w in range(i + 1, len(row)) if chart[c][w] == "K")
            t = (i - left) / (right - left)
            rec = {"chart": chart_name, "variant": variant, "stitch": "tuck" if stitch == "T"
                   else "miss", "wale": i, "course": c}
            for when in ("rest", "end"):
                ax, ay, az = axes[when]
                y = lambda key: float(P[key][ay])
                base = [(1 - t) * float(P[(left, c)][a]) + t * float(P[(right, c)][a])
                        for a in (ax, ay, az)]
                rec[f"held_loop_height_{when}_r"] = round((y((i, upper)) - y((i, below))) / r, 3)
                rec[f"tuck_loop_height_{when}_r"] = (
                    round((y((i, upper)) - base[1]) / r, 3) if stitch == "T" else "")
                if stitch == "M":
                    near = [p[2] for p in lines[when][c] if abs(p[0] - base[0]) < r]
                    rec[f"float_depth_{when}_r"] = round((base[2] - min(near)) / r, 3)
                else:
                    rec[f"float_depth_{when}_r"] = ""
            found.append(rec)
    return found


stitches = [rec for chart_name in ("single_tuck", "several_tucks", "several_misses")
            for variant in ("paper", "stabilised", "contact")
            for rec in stitch_rows(chart_name, variant)]
columns = ["chart", "variant", "stitch", "wale", "course"] + [
    f"{what}_{when}_r" for what in ("held_loop_height", "tuck_loop_height", "float_depth")
    for when in ("rest", "end")]
with open(f"{out}/stitch_features.csv", "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=columns)
    w.writeheader(); w.writerows(stitches)
