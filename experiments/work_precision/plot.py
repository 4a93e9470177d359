"""Work-precision diagrams from DIR/runs.csv (written by driver.py); reads nothing else.

  /usr/bin/python3 experiments/work_precision/plot.py DIR

Writes DIR/work_precision_cpu.png (position and coefficient error vs CPU time, one column per
scene) and DIR/work_precision_counts.png (position error vs RHS evaluations and vs
linear-solver set-ups). Log-log, one line per integrator (SciML style); runs that did not reach
equilibrium are drawn as open markers; extrapolated costs of the explicit methods as vertical
dashed lines at their estimated cost.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
rows = list(csv.DictReader(open(os.path.join(out, "runs.csv"))))
for r in rows:
    for k in ("rtol", "dt", "cpu_seconds", "rhs_evals", "lin_setups", "pos_err_m",
              "coeff_err_pct", "shape_err_m"):
        r[k] = float(r.get(k) or "nan")   # shape_err_m: empty in rows of an older runs.csv
scenes = list(dict.fromkeys(r["scene"] for r in rows))
integrators = list(dict.fromkeys(r["integrator"] for r in rows))
cmap = plt.get_cmap("tab20")
colour = {n: cmap(i % 20) for i, n in enumerate(integrators)}
FLOOR = 1e-13  # errors below are drawn at the floor (an exact match to the reference)


def panel(ax, scene, xkey, ykey, xlabel, ylabel):
    for name in integrators:
        rs = [r for r in rows if r["scene"] == scene and r["integrator"] == name]
        meas = sorted((r for r in rs if r["measured"] == "yes" and r[xkey] > 0
                       and math.isfinite(r[ykey])), key=lambda r: r[xkey])
        if meas:
            ax.plot([r[xkey] for r in meas], [max(r[ykey], FLOOR) for r in meas], "-",
                    color=colour[name], lw=1, label=name)
            for r in meas:
                filled = r["status"] == "equilibrium"
                ax.plot(r[xkey], max(r[ykey], FLOOR), "o", ms=4, color=colour[name],
                        mfc=colour[name] if filled else "none")
        for r in rs:
            if r["status"] == "extrapolated" and r[xkey] > 0:
                ax.axvline(r[xkey], color=colour[name], ls="--", lw=1,
                           label=name + " (extrapolated)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(scene)
    ax.grid(True, which="major", alpha=0.3)


def figure(panels, path, title):
    nrow, ncol = len(panels), len(panels[0])
    fig, axes = plt.subplots(nrow, ncol, figsize=(5 * ncol, 4 * nrow), squeeze=False)
    for i, row in enumerate(panels):
        for j, spec in enumerate(row):
            if spec is None:
                axes[i][j].axis("off")
            else:
                panel(axes[i][j], *spec)
    handles = {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    fig.legend(handles.values(), handles.keys(), loc="lower center", ncol=5, fontsize=8)
    fig.suptitle(title)
    fig.tight_layout(rect=(0, 0.1, 1, 0.96))
    fig.savefig(path, dpi=110)
    plt.close(fig)


drapes = [s for s in scenes if not s.startswith("knit")]


def err(s):
    """knit_contact: the shape error (README; the chart turns in its plane)."""
    return ("shape_err_m", "max shape error (m)") if s == "knit_contact" else \
        ("pos_err_m", "max position error (m)")


figure([[(s, "cpu_seconds", err(s)[0], "CPU time (s)", err(s)[1]) for s in scenes],
        [(s, "cpu_seconds", "coeff_err_pct", "CPU time (s)", "Eq. 5 coefficient error (%)")
         for s in drapes] + [None] * (len(scenes) - len(drapes))],
       os.path.join(out, "work_precision_cpu.png"),
       "Equilibrium error vs CPU time (open markers: equilibrium not reached)")
figure([[(s, "rhs_evals", err(s)[0], "RHS evaluations", err(s)[1]) for s in scenes],
        [(s, "lin_setups", err(s)[0], "linear-solver set-ups", err(s)[1]) for s in scenes]],
       os.path.join(out, "work_precision_counts.png"),
       "Equilibrium error vs RHS evaluations and linear-solver set-ups")
print("work_precision: wrote %s/work_precision_{cpu,counts}.png" % out)

# The tables of the README (summary.md) from the same CSV files.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
