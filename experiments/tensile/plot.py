"""Force-extension curves of experiments/tensile from curves.csv in DIR; reads nothing else.

  /usr/bin/python3 experiments/tensile/plot.py DIR

Writes DIR/tensile.png (force per width against strain, one panel per direction, loading solid,
unloading dashed; and the lateral strain) and runs summary.py (DIR/summary.md).
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
rows = list(csv.DictReader(open(os.path.join(out, "curves.csv"))))
fig, ax = plt.subplots(2, 2, figsize=(12, 9))
colors = {"plain": "tab:blue", "tuck": "tab:orange", "miss": "tab:green"}
for col, direction in enumerate(("wale", "course")):
    for kind, color in colors.items():
        run = [r for r in rows if r["chart"] == kind and r["direction"] == direction]
        if not run:
            continue
        strain = [float(r["strain"]) for r in run]
        top = strain.index(max(strain))
        for a, key in ((ax[0][col], "force_per_width_N_per_m"), (ax[1][col], "lateral_strain")):
            y = [float(r[key]) for r in run]
            a.plot(strain[:top + 1], y[:top + 1], "-o", color=color, ms=3, label=kind + " loading")
            a.plot(strain[top:], y[top:], "--", color=color, label=kind + " unloading")
    ax[0][col].set_title("pulled along the %ss" % direction)
    ax[0][col].set_ylabel("force per rest width (N/m)")
    ax[1][col].set_ylabel("lateral strain at mid-length")
    for a in ax[:, col]:
        a.set_xlabel("strain")
        a.grid(alpha=0.3)
    ax[0][col].legend(fontsize=8)
fig.suptitle("knitsim tensile: 24 x 24 charts, --gauge-ratio 2, default model (network + contact)")
fig.tight_layout()
fig.savefig(os.path.join(out, "tensile.png"), dpi=100)

# The tables of the README (summary.md) from the same CSV files.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
