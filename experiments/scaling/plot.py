#!/usr/bin/python3
"""Plots and growth exponents of the scaling study (reads only DIR/runs.csv of run.sh).

    /usr/bin/python3 experiments/scaling/plot.py DIR

Writes DIR/cost.png (CPU seconds and peak RSS against particles, log-log, one line per
solver; runs that did not reach equilibrium drawn hollow), DIR/fit.csv (per solver: the
least-squares exponent p of cpu ~ C particles^p and of steps ~ C particles^q over the runs
that reached equilibrium, with the number of points) and prints the fit table. Repeated runs
of one solver and grid (run.sh --target) enter as one point: the median CPU time of the rounds
(the status and steps of the median run); DIR/median.csv lists those points with the range.
Then summary.py writes DIR/summary.md, the tables of the README, from the same CSV files.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402  (the tables of summary.md; slope and medians are shared)
from summary import medians, slope  # noqa: E402


def main(out):
    rows = medians(list(csv.DictReader(open(out + "/runs.csv"))))
    with open(out + "/median.csv", "w", newline="") as f:
        keys = ["solver", "n", "particles", "integrated_dof", "status", "steps", "factorisations",
                "rounds", "cpu_median", "cpu_min", "cpu_max", "centre_sag_m", "residual",
                "factorization", "factor_nonzeros", "factor_flops", "factorisation_gflop"]
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    solvers = list(dict.fromkeys(r["solver"] for r in rows))
    fig, (ax_cpu, ax_mem) = plt.subplots(1, 2, figsize=(11, 4.5))
    fits = []
    for s in solvers:
        rs = [r for r in rows if r["solver"] == s and r["cpu_seconds"]]
        eq = [r for r in rs if r["status"] == "equilibrium"]
        p = [int(r["particles"]) for r in rs]
        line, = ax_cpu.plot(p, [float(r["cpu_seconds"]) for r in rs], "-", label=s)
        ax_cpu.plot([int(r["particles"]) for r in eq], [float(r["cpu_seconds"]) for r in eq], "o",
                    color=line.get_color())
        ax_cpu.plot([int(r["particles"]) for r in rs if r["status"] != "equilibrium"],
                    [float(r["cpu_seconds"]) for r in rs if r["status"] != "equilibrium"], "o",
                    mfc="none", color=line.get_color())
        ax_mem.plot(p, [float(r["max_rss_kb"]) / 1024 for r in rs], "o-", label=s)
        px = [int(r["particles"]) for r in eq]
        fits.append(dict(solver=s, points=len(eq),
                         cpu_exponent=slope(px, [float(r["cpu_seconds"]) for r in eq]),
                         steps_exponent=slope(px, [max(1, int(r["steps"])) for r in eq]),
                         largest_particles=max(px) if px else 0))
    for ax, label in ((ax_cpu, "CPU seconds per drape"), (ax_mem, "peak RSS (MiB)")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("particles")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    ax_cpu.set_title("four_corner, 50 cm sheet refined (hollow: not settled)")
    ax_mem.set_title("whole process, /usr/bin/time -v")
    ax_cpu.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out + "/cost.png", dpi=120)
    with open(out + "/fit.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(fits[0].keys()))
        w.writeheader()
        w.writerows(fits)
    print("%-16s %6s %12s %14s %10s" % ("solver", "points", "cpu exponent", "steps exponent",
                                         "largest"))
    for r in fits:
        fmt = lambda v: "-" if v is None else "%.2f" % v  # noqa: E731
        print("%-16s %6d %12s %14s %10d" % (r["solver"], r["points"], fmt(r["cpu_exponent"]),
                                             fmt(r["steps_exponent"]), r["largest_particles"]))
    summary.main([out])


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot.py DIR (the --out folder of run.sh)")
    main(sys.argv[1])
