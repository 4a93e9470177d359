#!/usr/bin/python3
"""Work-precision diagram of experiments/transient from DIR/runs.csv only:

  /usr/bin/python3 experiments/transient/plot.py DIR

Writes DIR/transient_cpu.png: per fixed time (one panel each), the error of the state at that
time against the tight reference vs the CPU of the run to it, log-log, one line per integrator
and setting sweep (SciML style); runs that did not reach the time are left out; extrapolated
costs of the stability-bound explicit methods are vertical dashed lines. Then runs summary.py.
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
times = sorted({float(r["time"]) for r in rows})
names = list(dict.fromkeys(r["integrator"] for r in rows))
cmap = plt.get_cmap("tab10")
colour = {n: cmap(i % 10) for i, n in enumerate(names)}
FLOOR = 1e-12
fig, axes = plt.subplots(1, len(times), figsize=(4.2 * len(times), 4), squeeze=False)
for ax, T in zip(axes[0], times):
    for n in names:
        rs = [r for r in rows if r["integrator"] == n and float(r["time"]) == T]
        meas = sorted((r for r in rs if r["measured"] == "yes"
                       and math.isfinite(float(r["error_m"]))), key=lambda r: float(r["cpu_seconds"]))
        if meas:
            ax.plot([float(r["cpu_seconds"]) for r in meas],
                    [max(float(r["error_m"]), FLOOR) for r in meas], "o-", ms=3, lw=1,
                    color=colour[n], label=n)
        for r in rs:
            if r["status"] == "extrapolated":
                ax.axvline(float(r["cpu_seconds"]), color=colour[n], ls="--", lw=1,
                           label=n + " (extrapolated cost)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU of the run to t (s)")
    ax.set_title("two_corner_slack, state at t = %g s" % T, fontsize=9)
    ax.grid(True, alpha=0.3)
axes[0][0].set_ylabel("max |x - x_ref| (m)")
axes[0][-1].legend(fontsize=6, loc="upper right")
fig.tight_layout()
fig.savefig(os.path.join(out, "transient_cpu.png"), dpi=110)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
