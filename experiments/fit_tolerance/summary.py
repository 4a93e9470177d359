#!/usr/bin/python3
"""Tables of experiments/fit_tolerance from its CSV files only (fits.csv, objective.csv) ->
summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/fit_tolerance/results)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import md_table, num, provenance, read_json, read_rows, summary_main  # noqa: E402

DEFAULT_RTOL = 1e-8  # knitsim fit's rtol (solvers/integrator.hpp): the CPU reference column


def objective(x):
    """An Eq. 5 objective: 6 decimals (0.090629) unless it is near zero (the twin's ~1e-8)."""
    return "%.6f" % float(x) if float(x) >= 1e-3 else num(x, 2)


def build(out):
    fits = sorted(read_rows(out, "fits.csv"), key=lambda r: float(r["rtol"]))
    obj = read_rows(out, "objective.csv")
    sections = []
    ref = [float(r["cpu_seconds"]) for r in fits if float(r["rtol"]) == DEFAULT_RTOL]
    rows = []
    for r in fits:
        rows.append([num(r["rtol"], exp=True), "%.2f" % float(r["stiffness"]),
                     "%.2f" % float(r["damping"]),
                     "%.2f" % float(r["elongation_limit"]),
                     "%.4f" % (100 * float(r["natural_length"])), r["topology"],
                     "%.6f" % float(r["objective"]),
                     "%s (%s)" % (r["evaluations"], r["failed_evaluations"]),
                     r["status"], "%.2f" % float(r["cpu_seconds"]),
                     "%.3f" % (float(r["cpu_seconds"]) / ref[0]) if ref else "—"])
    sections.append((
        "Fits at each rtol (fits.csv)",
        "`knitsim fit` with the same ICA budget and seed at each rtol; objective = Eq. 5, %; CPU = "
        "the fit process's user + system time.\n\n" + md_table(
            ["rtol", "fitted k (N/m)", "c (N·s/m)", "ε (%)", "L0 (cm)", "topology", "objective",
             "evaluations (failed)", "status", "fit CPU (s)",
             "CPU / CPU at rtol %s" % num(DEFAULT_RTOL, exp=True)],
            rows)))
    params = list(dict.fromkeys(r["params"] for r in obj))
    rtols = sorted({float(r["rtol"]) for r in obj})
    by = {(r["params"], float(r["rtol"])): r for r in obj}
    rows = []
    for rt in rtols:
        row = [num(rt, exp=True)]
        for p in params:
            r = by.get((p, rt))
            row += ["—"] * 4 if r is None else [objective(r["objective"]),
                                                 num(r["objective_change"], 2),
                                                 r["status"], r["steps"]]
        rows.append(row)
    head = ["rtol"]
    for p in params:
        head += ["%s: objective" % p, "change", "status", "steps"]
    worst = max(obj, key=lambda r: float(r["objective_change"])) if obj else None
    text = ("The Eq. 5 objective (%) of fixed parameter sets from `knitsim drape --target` at each "
            "rtol (no ICA); change = |objective - objective at the tightest rtol|.\n\n"
            + md_table(head, rows))
    if worst:
        text += ("\nLargest change: %s (%s, rtol %s).\n"
                 % (num(worst["objective_change"], 2), worst["params"],
                    num(worst["rtol"], exp=True)))
    sections.append(("Objective of fixed parameters at each rtol (objective.csv)", text))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return "fit_tolerance: tables", ["fits.csv", "objective.csv", "manifest.json"], sections


def main(argv=None):
    return summary_main("fit_tolerance", build, argv)


if __name__ == "__main__":
    main()
