#!/usr/bin/python3
"""Plot of experiments/fit_tolerance from its CSV only: fit CPU and fitted objective vs rtol,
and the objective change of fixed parameter sets vs rtol -> fit_tolerance.png.
Usage: plot.py OUT"""
import csv
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
fits = sorted(csv.DictReader(open(os.path.join(out, "fits.csv"))), key=lambda r: float(r["rtol"]))
obj = list(csv.DictReader(open(os.path.join(out, "objective.csv"))))
fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
rt = [float(r["rtol"]) for r in fits]
axes[0].plot(rt, [float(r["cpu_seconds"]) for r in fits], "o-")
axes[0].set_ylabel("fit CPU (s)")
axes[1].plot(rt, [float(r["objective"]) for r in fits], "o-")
axes[1].set_ylabel("fitted objective (Eq. 5)")
for name in sorted({r["params"] for r in obj}):
    rows = sorted((r for r in obj if r["params"] == name), key=lambda r: float(r["rtol"]))
    axes[2].plot([float(r["rtol"]) for r in rows],
                 [max(float(r["objective_change"]), 1e-16) for r in rows], "o-", label=name)
axes[2].set_ylabel("|objective - objective at tightest rtol|")
axes[2].set_yscale("log")
axes[2].legend(fontsize=7)
for ax in axes:
    ax.set_xscale("log")
    ax.set_xlabel("rtol")
fig.suptitle("knitsim fit, four_corner twin target, same ICA budget and seed", fontsize=9)
fig.tight_layout()
fig.savefig(os.path.join(out, "fit_tolerance.png"), dpi=120)

# The tables of the README (summary.md) from the same CSV files.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
