#!/usr/bin/python3
"""Work-precision diagrams of experiments/transient from DIR/runs.csv (and DIR/ringing.csv) only:

  /usr/bin/python3 experiments/transient/plot.py DIR

Writes, per case in runs.csv, a PNG with one panel per fixed time: the error of the state at that
time against the tight reference vs the CPU of the run to it, log-log, one line per integrator
and setting sweep (SciML style); runs that did not reach the time are left out; extrapolated
costs of the stability-bound explicit methods are vertical dashed lines:
  transient_cpu.png       two_corner_slack (error in m);
  transient_knit_cpu.png  single_tuck, the knit tuck's ringing (error in loop radii r).
From ringing.csv, transient_knit_ringing.png: the knit reference's largest displacement, its
distance to the settled state and its largest speed against time, the fixed times marked.
Then runs summary.py.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

out = sys.argv[1]
rows = list(csv.DictReader(open(os.path.join(out, "runs.csv"))))
FILES = {"two_corner_slack": "transient_cpu.png", "single_tuck": "transient_knit_cpu.png"}
FLOOR = 1e-12
cmap = plt.get_cmap("tab10")
knit_times = []
for case in dict.fromkeys(r["scene"] for r in rows):
    sh = dict(summary.DEFAULT_SHOW)
    sh.update(summary.SHOW.get(case, {}))
    err, floor = sh["err"], FLOOR if sh["err"] == "error_m" else 1e-13  # r: 8.9e-18 m
    rs_case = [r for r in rows if r["scene"] == case]
    times = sorted({float(r["time"]) for r in rs_case})
    if case == "single_tuck":
        knit_times = times
    names = list(dict.fromkeys(summary.sweep_name(r) for r in rs_case))
    colour = {n: cmap(i % 10) for i, n in enumerate(names)}
    style = {n: ("o-" if i < 10 else "s--") for i, n in enumerate(names)}
    fig, axes = plt.subplots(1, len(times), figsize=(4.2 * len(times), 4), squeeze=False)
    for ax, T in zip(axes[0], times):
        for n in names:
            rs = [r for r in rs_case if summary.sweep_name(r) == n and float(r["time"]) == T]
            meas = sorted((r for r in rs if r["measured"] == "yes"
                           and math.isfinite(float(r[err]))),
                          key=lambda r: float(r["cpu_seconds"]))
            if meas:
                ax.plot([float(r["cpu_seconds"]) for r in meas],
                        [max(float(r[err]), floor) for r in meas], style[n], ms=3, lw=1,
                        color=colour[n], label=n)
            for r in rs:
                if r["status"] == "extrapolated":
                    ax.axvline(float(r["cpu_seconds"]), color=colour[n], ls="--", lw=1,
                               label=n + " (extrapolated cost)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU of the run to t (s)")
        ax.set_title("%s, state at t = %g %s" % (case, T * sh["t_scale"], sh["t_unit"]),
                     fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel("max |x - x_ref| (%s)" % sh["err_unit"])
    axes[0][-1].legend(fontsize=6, loc="upper right")
    fig.tight_layout()
    fig.savefig(os.path.join(out, FILES.get(case, "transient_%s_cpu.png" % case)), dpi=110)
    plt.close(fig)

ringing_path = os.path.join(out, "ringing.csv")
if os.path.exists(ringing_path):
    ring = list(csv.DictReader(open(ringing_path)))
    t = [float(r["time"]) * 1e6 for r in ring]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8))
    a1.plot(t, [float(r["max_displacement_over_r"]) for r in ring], "o-", ms=3,
            label="largest displacement from rest (r)")
    a1.plot(t, [float(r["distance_to_settled_over_r"]) for r in ring], "s-", ms=3,
            label="distance to the settled state (r)")
    a1.set_xlim(0, 300)
    a1.set_xlabel("t (us)")
    a1.set_title("single_tuck: the pull and the first oscillations", fontsize=9)
    a2.semilogy(t, [float(r["distance_to_settled_over_r"]) for r in ring], "s-", ms=3,
                color="C1", label="distance to the settled state (r)")
    a2.semilogy(t, [float(r["max_speed_m_per_s"]) for r in ring], "^-", ms=3, color="C2",
                label="largest speed (m/s)")
    a2.set_xlabel("t (us)")
    a2.set_title("single_tuck: the decay", fontsize=9)
    for ax in (a1, a2):
        for T in knit_times:
            ax.axvline(T * 1e6, color="grey", ls=":", lw=1)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "transient_knit_ringing.png"), dpi=110)
    plt.close(fig)

summary.main([out])
