#!/usr/bin/python3
"""Summary tables of experiments/optimizers from its CSV files only (runs.csv, trace.csv,
reference.csv, manifest.json) -> summary.md and summary.csv; the README points at them.
Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/optimizers/results)

summary.csv (written next to the CSV, only when FILE is the default) and the first table of
summary.md: per optimizer the median, quartiles, min and max of the final error, evaluations and
CPU seconds of a run, and the median evaluations and CPU seconds to reach each threshold: the
median final ICA error, 1.01 x and 1.1 x the best error any run found, the Table 4 error; "not
reached" when fewer than half the seeds reached it (a seed that never reached it counts as
infinitely late). The second table: where the runs ended (grid size n = cells, topology) and
the CPU per drape evaluation.
"""
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, median, percentile, provenance, read_json,  # noqa: E402
                    read_rows, summary_main)

ORDER = ["ica", "de", "sade", "cmaes", "pso", "lm"]


def reach(points, threshold):
    """(evaluation, cpu seconds) of the first best-so-far <= threshold, or (inf, inf)."""
    for p in points:
        if p["best"] <= threshold:
            return p["evaluation"], p["cpu"]
    return math.inf, math.inf


def median_or_none(values):
    m = median(values) if values else math.inf
    return m if math.isfinite(m) else None


def fmt(x):  # errors differ in the 4th digit near the optimum
    return "%.5g" % x if isinstance(x, float) else str(x)


def summary_rows(out):
    """(thresholds, fields, rows) of summary.csv."""
    runs = read_rows(out, "runs.csv")
    traces = {}
    for r in read_rows(out, "trace.csv"):
        traces.setdefault((r["optimizer"], int(r["seed"])), []).append(
            {"evaluation": int(r["evaluation"]), "best": float(r["best_so_far"]),
             "cpu": float(r["cpu_seconds"])})
    reference = {r["reference"]: float(r["error"]) for r in read_rows(out, "reference.csv")}
    truth = reference.get("table4_parameters")
    names = [n for n in ORDER if any(r["optimizer"] == n for r in runs)]
    final = {n: [float(r["final_error"]) for r in runs if r["optimizer"] == n] for n in names}
    if not final:
        return [], [], []
    best_any = min(min(v) for v in final.values())
    thresholds = []
    if "ica" in final:
        thresholds.append(("ica_median", median(final["ica"])))
    thresholds.append(("best_x1.01", 1.01 * best_any))
    thresholds.append(("best_x1.1", 1.1 * best_any))
    if truth is not None:
        thresholds.append(("table4", truth))
    fields = ["optimizer", "runs", "median", "q1", "q3", "min", "max", "evaluations",
              "cpu_seconds"]
    for t, _ in thresholds:
        fields += ["%s_evaluations" % t, "%s_cpu_seconds" % t, "%s_reached" % t]
    rows = []
    for n in names:
        mine = [r for r in runs if r["optimizer"] == n]
        seeds = [int(r["seed"]) for r in mine]
        v = final[n]
        row = {"optimizer": n, "runs": len(v), "median": median(v),
               "q1": percentile(v, 25), "q3": percentile(v, 75), "min": min(v), "max": max(v),
               "evaluations": median([r["evaluations"] for r in mine]),
               "cpu_seconds": median([r["cpu_seconds"] for r in mine])}
        for t, value in thresholds:
            hits = [reach(traces.get((n, s), []), value) for s in seeds]
            e = median_or_none([h[0] for h in hits])
            c = median_or_none([h[1] for h in hits])
            row["%s_evaluations" % t] = "not reached" if e is None else "%g" % e
            row["%s_cpu_seconds" % t] = "not reached" if c is None else "%.3g" % c
            row["%s_reached" % t] = "%d/%d" % (sum(math.isfinite(h[0]) for h in hits), len(hits))
        rows.append(row)
    return thresholds, fields, rows


def build(out):
    thresholds, fields, rows = summary_rows(out)
    if not rows:
        return ("optimizers: tables", ["runs.csv", "trace.csv", "reference.csv", "manifest.json"],
                [("Provenance", provenance(read_json(out, "manifest.json")))])
    text = "Thresholds: " + ", ".join("%s = %.5g %%" % t for t in thresholds) + "\n\n"
    head = ["optimizer", "runs", "median %", "IQR %", "min-max %", "evals", "CPU s"]
    for t, _ in thresholds:
        head += ["evals to %s" % t, "CPU s to %s" % t]
    cells = []
    for r in rows:
        c = [r["optimizer"], str(r["runs"]), fmt(r["median"]),
             "%s-%s" % (fmt(r["q1"]), fmt(r["q3"])),
             "%s-%s" % (fmt(r["min"]), fmt(r["max"])), fmt(r["evaluations"]),
             fmt(r["cpu_seconds"])]
        for t, _ in thresholds:
            c += ["%s (%s)" % (r["%s_evaluations" % t], r["%s_reached" % t]),
                  r["%s_cpu_seconds" % t]]
        cells.append(c)
    sections = [("Final error and evaluations to each threshold (runs.csv, trace.csv, "
                 "reference.csv)",
                 "Errors in % (Eq. 5); medians over the seeds; \"(k/n)\" = seeds that reached "
                 "the threshold.\n\n" + text + md_table(head, cells))]

    runs = read_rows(out, "runs.csv")
    rows = []
    for n in [o for o in ORDER if any(r["optimizer"] == o for r in runs)]:
        mine = [r for r in runs if r["optimizer"] == n]
        ns = sorted({int(r["cells"]) for r in mine}, reverse=True)
        per_n = ", ".join("n = %d: %d" % (c, sum(int(r["cells"]) == c for r in mine)) for c in ns)
        best_n = {}
        for r in mine:
            c = int(r["cells"])
            best_n[c] = min(best_n.get(c, math.inf), float(r["final_error"]))
        topo = ", ".join("%s: %d" % (t, sum(r["topology"] == t for r in mine))
                         for t in sorted({r["topology"] for r in mine}))
        ms = [1000 * float(r["cpu_seconds"]) / int(r["evaluations"]) for r in mine]
        rows.append([n, per_n, ", ".join("n = %d: %.5g" % (c, best_n[c]) for c in ns), topo,
                     "%.0f (%.0f-%.0f)" % (median(ms), min(ms), max(ms)),
                     ", ".join(sorted({r["stop"] for r in mine}))])
    sections.append((
        "Where the runs ended and the cost of an evaluation (runs.csv)",
        "n = cells per side of the fitted grid (L0 = W / n); the best final error among the "
        "runs that ended in each n; CPU per drape evaluation = the run's CPU seconds / its "
        "evaluations, median (range) over the seeds.\n\n" + md_table(
            ["optimizer", "runs ending in each n", "best final error % in each n",
             "fitted topology", "ms CPU per evaluation", "stop"], rows)))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return ("optimizers: tables", ["runs.csv", "trace.csv", "reference.csv", "manifest.json"],
            sections)


def write_csv(out):
    _, fields, rows = summary_rows(out)
    if not rows:
        return
    with open(os.path.join(out, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: fmt(v) for k, v in r.items()})


def main(argv=None):
    text = summary_main("optimizers", build, argv)
    args = sys.argv[1:] if argv is None else argv
    if "--output" not in args:
        write_csv(args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                     "results"))
    return text


if __name__ == "__main__":
    main()
