"""Plots and the summary table of experiments/optimizers from its CSV files only.

    plot.py OUT

Reads OUT/runs.csv, OUT/trace.csv, OUT/reference.csv (knitsim_optimizers); writes
  convergence.png   best-so-far error against drape evaluations and against CPU seconds: median
                    over the seeds and the interquartile band, per optimizer; dashed: the error of
                    the Table 4 parameters (for a twin target, the truth);
  final_errors.png  final error per optimizer: box (quartiles, whiskers at min/max) and one dot
                    per seed;
  both as the excess over the best error of all runs, log scale (1e-6 % = reached it);
  summary.csv, summary.md  by summary.py (standard library only; see its docstring): per
                    optimizer the final error, evaluations, CPU and the evaluations to each
                    threshold, where the runs ended, the cost of an evaluation.
"""
import csv
import os
import sys
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

ORDER = ["ica", "de", "sade", "cmaes", "pso", "lm"]
COLORS = {"ica": "C3", "de": "C0", "sade": "C1", "cmaes": "C2", "pso": "C4", "lm": "k"}


def read(out, name):
    return list(csv.DictReader(open(os.path.join(out, name))))


def step(points, grid, key):
    """Best-so-far at each grid value of `key` ("evaluation" or "cpu"); nan outside the run."""
    xs = np.array([p[key] for p in points])
    ys = np.array([p["best"] for p in points])
    idx = np.searchsorted(xs, grid, side="right") - 1
    res = np.where(idx >= 0, ys[np.maximum(idx, 0)], np.nan)
    return np.where(grid <= xs[-1], res, np.nan)  # nan after the run's last evaluation


def main(out):
    runs = read(out, "runs.csv")
    traces = {}
    for r in read(out, "trace.csv"):
        traces.setdefault((r["optimizer"], int(r["seed"])), []).append(
            {"evaluation": int(r["evaluation"]), "best": float(r["best_so_far"]),
             "cpu": float(r["cpu_seconds"])})
    reference = {r["reference"]: float(r["error"]) for r in read(out, "reference.csv")}
    truth = reference.get("table4_parameters")
    names = [n for n in ORDER if any(r["optimizer"] == n for r in runs)]
    final = {n: [float(r["final_error"]) for r in runs if r["optimizer"] == n] for n in names}
    budget = max(int(r["budget"]) for r in runs)
    # The plots show the excess over the best error of all runs (log scale), which resolves the
    # last digits where the optimizers differ; excesses below FLOOR are drawn at FLOOR.
    best_any = min(min(v) for v in final.values())
    floor = 1e-6

    def excess(e):
        return np.maximum(np.asarray(e, dtype=float) - best_any, floor)

    # convergence.png
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    max_cpu = max(p["cpu"] for t in traces.values() for p in t)
    min_cpu = min(p["cpu"] for t in traces.values() for p in t)
    grids = {"evaluation": np.arange(1, budget + 1),
             "cpu": np.geomspace(min_cpu, max_cpu, 400)}
    for ax, key, label in ((axes[0], "evaluation", "drape evaluations"),
                           (axes[1], "cpu", "CPU seconds")):
        grid = grids[key]
        for n in names:
            curves = np.array([step(traces[(n, int(r["seed"]))], grid, key)
                               for r in runs if r["optimizer"] == n])
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # all-nan columns: no run there
                ok = np.sum(np.isfinite(curves), axis=0) * 2 > len(curves)  # most seeds running
                med = np.nanmedian(np.where(np.isfinite(curves), curves, np.nan), axis=0)
                q1 = np.nanpercentile(curves, 25, axis=0)
                q3 = np.nanpercentile(curves, 75, axis=0)
            ax.plot(grid[ok], excess(med[ok]), color=COLORS[n], drawstyle="steps-post",
                    label="%s (%d seeds)" % (n, len(curves)))
            ax.fill_between(grid[ok], excess(q1[ok]), excess(q3[ok]), color=COLORS[n],
                            alpha=0.15, lw=0, step="post")
        if truth is not None:
            ax.axhline(truth - best_any, color="gray", ls="--", lw=1, label="Table 4 parameters")
        ax.set_xlabel(label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("best-so-far error - %.5f %%" % best_any)
    axes[0].set_title("median and interquartile band over seeds")
    axes[1].set_title("against CPU time (one thread)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "convergence.png"), dpi=90)
    plt.close(fig)

    # final_errors.png
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.boxplot([excess(final[n]) for n in names], labels=names, whis=(0, 100), widths=0.5)
    rng = np.random.default_rng(0)
    for i, n in enumerate(names):
        ax.scatter(i + 1 + rng.uniform(-0.12, 0.12, len(final[n])), excess(final[n]), s=14,
                   color=COLORS[n], zorder=3)
    if truth is not None:
        ax.axhline(truth - best_any, color="gray", ls="--", lw=1, label="Table 4 parameters")
        ax.legend(fontsize=8)
    ax.set_yscale("log")
    ax.set_ylabel("final error - %.5f %% (best of all runs)" % best_any)
    ax.set_title("final error after %d drape evaluations (lm: its own count)" % budget)
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "final_errors.png"), dpi=90)
    plt.close(fig)

    # summary.md / summary.csv: the tables, by summary.py from the same CSV files.
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import summary
    summary.main([out])


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot.py OUT")
    main(sys.argv[1])
