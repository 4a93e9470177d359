#!/usr/bin/python3
"""Plots of experiments/stability from its CSV files only:
  map.png     per method (euler, verlet): the dt x stiffness map (colour = log10 max position
              error vs cvode-bdf at t_end, x = unstable) with the limit lines of limits.csv
              (predicted = Gershgorin, estimated = Lanczos-capped, exact = linear analysis,
              measured = bisection);
  limits.png  measured / predicted and measured / exact for every case and method;
  spurious.png per scene and run (integrator and setting) of spurious.csv: where it ended
              (same equilibrium as the dynamics' reference, another minimum, spurious, saddle,
              no equilibrium, or an "equilibrium" above the reference run's total energy that
              knitsim did not flag) and how far from the reference (m).
Usage: plot.py OUT (reads OUT/limits.csv, OUT/map.csv, OUT/spurious.csv; writes the PNGs into
OUT)."""
import csv
import math
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
limits = list(csv.DictReader(open(os.path.join(out, "limits.csv"))))
cells = list(csv.DictReader(open(os.path.join(out, "map.csv"))))
f = lambda r, k: float(r[k])

fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
for ax, method in zip(axes, ("euler", "verlet")):
    mc = [c for c in cells if c["method"] == method]
    stable = [c for c in mc if c["stable"] == "1"]
    errs = [max(f(c, "error_m"), 1e-16) for c in stable]
    sc = ax.scatter([f(c, "stiffness") for c in stable], [f(c, "dt") for c in stable],
                    c=[math.log10(e) for e in errs], cmap="viridis", s=80, marker="s")
    bad = [c for c in mc if c["stable"] != "1"]
    ax.scatter([f(c, "stiffness") for c in bad], [f(c, "dt") for c in bad], c="red", marker="x",
               s=50, label="unstable")
    line = sorted((r for r in limits if r["method"] == method and r["group"] in ("base", "stiffness")),
                  key=lambda r: f(r, "stiffness"))
    k = [f(r, "stiffness") for r in line]
    for key, style in (("predicted", "k--"), ("estimated", "k:"), ("exact", "k-"),
                       ("measured", "wo")):
        ax.plot(k, [f(r, key) for r in line], style, mec="k", label=key + " limit")
    ax.set_xscale("log"); ax.set_yscale("log")
    ax.set_xlabel("stiffness k (N/m)")
    t_end = mc[0]["t_end"] if mc else "?"
    ax.set_title("%s: c 12 N s/m, 41.65 g/m^2, L0 4.9 cm, run to t = %s s" % (method, t_end),
                 fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    fig.colorbar(sc, ax=ax, label="log10 max position error (m)")
axes[0].set_ylabel("dt (s)")
fig.tight_layout()
fig.savefig(os.path.join(out, "map.png"), dpi=110)

fig, ax = plt.subplots(figsize=(11, 4.2))
labels = []
for i, r in enumerate(limits):
    labels.append("%s %s" % (r["case"], r["method"]))
    for key, mk, col in (("measured_over_predicted", "v", "tab:orange"),
                         ("measured_over_estimated", "^", "tab:green"),
                         ("measured_over_exact", "o", "tab:blue")):
        v = f(r, key)
        if math.isfinite(v):
            ax.plot(i, v, mk, color=col, label=key if i == 0 or not ax.get_legend_handles_labels()[1].count(key) else None)
ax.axhline(1.0, color="k", lw=0.6)
ax.axhspan(0.95, 1.05, color="0.9")
ax.set_xticks(range(len(labels)))
ax.set_xticklabels(labels, rotation=90, fontsize=5)
ax.set_ylabel("measured / linear-analysis limit")
ax.legend(fontsize=8)
ax.set_title("Stability limits: measured vs predict_stable_dt (Gershgorin), estimate_stable_dt "
             "(Lanczos-capped) and exact linear analysis",
             fontsize=9)
fig.tight_layout()
fig.savefig(os.path.join(out, "limits.png"), dpi=110)

spurious_path = os.path.join(out, "spurious.csv")
if os.path.exists(spurious_path):
    sp = list(csv.DictReader(open(spurious_path)))
    scenes = list(dict.fromkeys(r["scene"] for r in sp))
    runs = list(dict.fromkeys((r["integrator"], r["setting"]) for r in sp))
    colours = {"same equilibrium": "tab:green", "another minimum": "tab:blue",
               "spurious (energy above the reference)": "tab:red", "saddle": "tab:purple"}
    fig, ax = plt.subplots(figsize=(2.2 + 2.3 * len(scenes), 0.6 + 0.27 * len(runs)))
    # A state above the reference run's total energy (once the pins stopped) that knitsim still
    # called an equilibrium: unreachable by the dynamics, not flagged (orange).
    e_dyn = {r["scene"]: float(r["energy_reference"]) for r in sp if r["setting"] == "reference"}
    for r in sp:
        x, y = scenes.index(r["scene"]), runs.index((r["integrator"], r["setting"]))
        c = colours.get(r["outcome"], "tab:gray")
        if r["status"] == "equilibrium" and float(r["energy"]) > e_dyn[r["scene"]]:
            c, r["outcome"] = "tab:orange", "above the dynamics' energy, not flagged"
        ax.add_patch(plt.Rectangle((x - 0.45, y - 0.4), 0.9, 0.8, color=c, alpha=0.75))
        d = float(r["distance_m"])
        ax.text(x, y, "%s, %s m" % (r["outcome"].split(" (")[0], "%.2g" % d if math.isfinite(d)
                                    else "?"), ha="center", va="center", fontsize=6)
    ax.set_xlim(-0.5, len(scenes) - 0.5)
    ax.set_ylim(len(runs) - 0.5, -0.5)
    ax.set_xticks(range(len(scenes)))
    ax.set_xticklabels(scenes, fontsize=8)
    ax.set_yticks(range(len(runs)))
    ax.set_yticklabels(["%s %s" % r for r in runs], fontsize=7)
    ax.set_title("End states against the dynamics' equilibrium (cvode-bdf rtol 1e-8); grey: no "
                 "equilibrium (t_max, failure, wall cap)", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "spurious.png"), dpi=110)

# The tables of the README (summary.md) from the same CSV files.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
