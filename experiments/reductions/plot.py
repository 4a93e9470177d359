#!/usr/bin/python3
"""Plot of experiments/reductions from its CSV only: CPU of each variant relative to the
reduced default (cvode-bdf, stop at equilibrium, topology a; for the symmetry-reduced half,
quarter and eighth: relative to the full grid of the same scene, n and integrator) ->
reductions.png.
Usage: plot.py OUT"""
import csv
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
read = lambda name: list(csv.DictReader(open(os.path.join(out, name))))
stop, static, topo = read("stop.csv"), read("static.csv"), read("topology.csv")
labels, vals = [], []
for r in stop:
    labels.append("%s\n%s" % (r["scene"], r["stop"])); vals.append(float(r["cpu_ratio"]))
for r in static:
    if r["integrator"] == "static":
        labels.append("%s\nstatic (relax + Newton)" % r["scene"]); vals.append(float(r["cpu_ratio"]))
a = [r for r in topo if r["topology"] == "a"][0]
for r in topo:
    if r["topology"] != "a":
        labels.append("four_corner euler step\ntopology %s (%s springs)" % (r["topology"], r["springs"]))
        vals.append(float(r["euler_us_per_step"]) / float(a["euler_us_per_step"]))
if os.path.exists(os.path.join(out, "symmetry.csv")):
    for r in read("symmetry.csv"):
        if r["model"] != "full":
            labels.append("%s n=%s %s\n%s (%s dof)" % (r.get("scene", "four_corner"), r["n"],
                                                       r["integrator"], r["model"], r["dof"]))
            vals.append(1.0 / float(r["speedup"]))
fig, ax = plt.subplots(figsize=(12, 5.5))
ax.bar(range(len(vals)), vals, color="tab:blue")
ax.axhline(1.0, color="k", lw=0.7)
ax.set_xticks(range(len(vals)))
ax.set_xticklabels(labels, fontsize=6, rotation=40, ha="right")
ax.set_ylabel("CPU relative to the reduced default")
for i, v in enumerate(vals):
    ax.text(i, v, "%.3g" % v, ha="center", va="bottom", fontsize=7)
ax.set_title("Reductions: equilibrium stop vs fixed end time, static polish, springs per topology, "
             "half, quarter and eighth by symmetry",
             fontsize=9)
fig.tight_layout()
fig.savefig(os.path.join(out, "reductions.png"), dpi=120)

# The tables of the README (summary.md) from the same CSV files.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
