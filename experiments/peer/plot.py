#!/usr/bin/python3
"""Plot of experiments/peer from compare.csv only: CPU per drape to equilibrium, knitsim
cvode-bdf vs scipy BDF, per scene (writes peer.png). Usage: plot.py OUT"""
import csv
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
rows = list(csv.DictReader(open(os.path.join(out, "compare.csv"))))
labels, vals, colors = [], [], []
for r in rows:
    if not any(l.startswith(r["scene"] + "\nscipy") for l in labels):
        labels.append("%s\nscipy BDF rtol %s" % (r["scene"], r["scipy_rtol"]))
        vals.append(float(r["scipy_cpu"]))
        colors.append("tab:gray")
    model = r.get("knitsim_model", "full")
    labels.append("%s\nknitsim rtol %s%s" % (r["scene"], r["knitsim_rtol"],
                                             "" if model == "full" else "\non the " + model))
    vals.append(float(r["knitsim_cpu_median"]))
    colors.append("tab:blue" if model == "full" else "tab:green")
fig, ax = plt.subplots(figsize=(8, 4))
ax.bar(range(len(vals)), vals, color=colors)
ax.set_yscale("log")
ax.set_xticks(range(len(vals)))
ax.set_xticklabels(labels, fontsize=7)
ax.set_ylabel("CPU seconds per drape to equilibrium")
for i, v in enumerate(vals):
    ax.text(i, v, "%.3g s" % v, ha="center", va="bottom", fontsize=7)
ax.set_title("knitsim cvode-bdf vs independent scipy BDF (same residual stop 1e-8)", fontsize=9)
fig.tight_layout()
fig.savefig(os.path.join(out, "peer.png"), dpi=120)

# The tables of the README (summary.md) from the same CSV files.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
