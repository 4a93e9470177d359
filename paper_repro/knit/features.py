#!/usr/bin/env python3
"""Measured features of the tuck and miss charts across the variants (paper, stabilised,
contact), read from each run's stitches.csv: the product's textile measures (docs/knit.md,
"Textile measures"; src/measure/knit_measures.hpp), nothing measured here.

Usage: /usr/bin/python3 paper_repro/knit/features.py OUT  (OUT = make_figures.sh's folder)
Writes OUT/features.csv (single_tuck) and OUT/stitch_features.csv (every tuck and miss of
single_tuck, several_tucks and several_misses). Lengths in loop radii r (summary.json's
params.loop_radius); stitches.csv's columns, per chart cell (wale from the left, course from the
bottom): a loop's height is the extent along y of its centreline arc (a knit's foot to foot, a
tuck's sinker to sinker), its centre the arc's centroid, a cell's yarn length sinker to sinker;
"0" columns are at rest.

features.csv, single_tuck (the tuck at wale 3, course 2; the loop it holds at wale 3, course 1):
  held_loop_height_start_r, held_loop_height_end_r: the held loop's height at rest and at the end.
  held_loop_centre_rise_r, tuck_loop_centre_rise_r: y - y0 of the held loop's and the tuck
      loop's centres.
  lateral_dx_toward_tuck_r_d<k>: x - x0 of the centres of the loops of the tuck's course k wales
      either side of it, signed + toward the tuck, averaged over the two sides.
stitch_features.csv, per tuck or miss cell at wale i, course c:
  held_loop_height_*_r: the knit loop on needle i below it (the highest knit course c' < c;
      cells stacked on one needle share it), at rest and at the end.
  held_loop_length_*_r: that loop's yarn length (held over the courses above it).
  tuck_loop_height_*_r, tuck_loop_length_*_r (tucks): the tuck loop's height and length.
  float_depth_*_r, float_length_*_r (misses): how far the float passes behind the face (the
      feet of the knit loops either side) and the whole float's length."""
import csv
import json
import sys

out = sys.argv[1]


def run(chart, variant):
    """(r, {(wale, course): stitches.csv row}) of one run of make_figures.sh."""
    d = f"{out}/{chart}-{variant}"
    r = json.load(open(f"{d}/summary.json"))["params"]["loop_radius"]
    rows = {(int(s["wale"]), int(s["course"])): s for s in csv.DictReader(open(f"{d}/stitches.csv"))}
    return r, rows


def in_r(value, r):
    return round(float(value) / r, 3) if value != "" else ""


rows = []
for variant in ("paper", "stabilised", "contact"):
    r, S = run("single_tuck", variant)
    held, tuck = S[(3, 1)], S[(3, 2)]
    rise = lambda s: round((float(s["y_m"]) - float(s["y0_m"])) / r, 3)
    row = {"chart": "single_tuck", "variant": variant,
           "held_loop_height_start_r": in_r(held["loop_height0_m"], r),
           "held_loop_height_end_r": in_r(held["loop_height_m"], r),
           "held_loop_centre_rise_r": rise(held),
           "tuck_loop_centre_rise_r": rise(tuck)}
    for k in range(1, 5):
        v = []
        for side in (-1, 1):
            key = (3 + side * k, 2)
            if key in S:  # + toward the tuck
                v.append(-side * (float(S[key]["x_m"]) - float(S[key]["x0_m"])) / r)
        row[f"lateral_dx_toward_tuck_r_d{k}"] = round(sum(v) / len(v), 3)
    rows.append(row)
with open(f"{out}/features.csv", "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=list(rows[0]))
    w.writeheader(); w.writerows(rows)
print(open(f"{out}/features.csv").read())


def stitch_rows(chart, variant):
    r, S = run(chart, variant)
    found = []
    for (i, c), s in sorted(S.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        if s["stitch"] not in "TM":
            continue
        below = S[(i, max(k for (w, k), q in S.items() if w == i and k < c and q["stitch"] == "K"))]
        rec = {"chart": chart, "variant": variant,
               "stitch": "tuck" if s["stitch"] == "T" else "miss", "wale": i, "course": c}
        for when, z in (("rest", "0"), ("end", "")):
            tuck = s["stitch"] == "T"
            rec[f"held_loop_height_{when}_r"] = in_r(below[f"loop_height{z}_m"], r)
            rec[f"held_loop_length_{when}_r"] = in_r(below[f"yarn_length{z}_m"], r)
            rec[f"tuck_loop_height_{when}_r"] = in_r(s[f"loop_height{z}_m"], r) if tuck else ""
            rec[f"tuck_loop_length_{when}_r"] = in_r(s[f"yarn_length{z}_m"], r) if tuck else ""
            rec[f"float_depth_{when}_r"] = in_r(s[f"float_depth{z}_m"], r)
            rec[f"float_length_{when}_r"] = in_r(s[f"float_length{z}_m"], r)
        found.append(rec)
    return found


stitches = [rec for chart in ("single_tuck", "several_tucks", "several_misses")
            for variant in ("paper", "stabilised", "contact")
            for rec in stitch_rows(chart, variant)]
columns = ["chart", "variant", "stitch", "wale", "course"] + [
    f"{what}_{when}_r" for what in ("held_loop_height", "held_loop_length", "tuck_loop_height",
                                    "tuck_loop_length", "float_depth", "float_length")
    for when in ("rest", "end")]
with open(f"{out}/stitch_features.csv", "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=columns)
    w.writeheader(); w.writerows(stitches)
