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
import csv, json, sys
out = sys.argv[1]
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
