#!/usr/bin/python3
"""Tables of experiments/transient from its CSV files only (runs.csv, references.csv,
manifest.json) -> summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/transient/results)
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import md_table, num, provenance, read_json, read_rows, summary_main  # noqa: E402

LEVELS = [1e-2, 1e-4, 1e-6, 1e-8]  # m: accuracy levels of the "cheapest" table


def setting(r):
    return ("rtol %s" % num(r["rtol"], exp=True)) if float(r["rtol"]) > 0 else \
        ("dt %s s" % num(r["dt"]))


def sweeps(runs):
    """{(integrator, setting): {time: row}} of the measured runs."""
    out = {}
    for r in runs:
        if r["measured"] == "yes":
            out.setdefault((r["integrator"], setting(r)), {})[float(r["time"])] = r
    return out


def build(out):
    runs = read_rows(out, "runs.csv")
    refs = read_rows(out, "references.csv")
    times = sorted({float(r["time"]) for r in runs})
    sections = []
    sections.append(("References (references.csv)", md_table(
        ["t (s)", "integrator", "rtol / atol", "status", "steps", "CPU (s)",
         "distance to the rtol %s run (m)" % (num(refs[0]["check_rtol"], exp=True) if refs else "")],
        [[num(r["time"]), r["integrator"], "%s / %s" % (num(r["rtol"], exp=True),
                                                        num(r["atol"], exp=True)),
          r["status"], r["steps"], num(r["cpu_seconds"]), num(r["check_distance_m"], 2)]
         for r in refs])))

    # Every setting: error at each time and the CPU of the run to the last one.
    sw = sweeps(runs)
    T_last = times[-1] if times else 0
    rows = []
    for (integ, s), by_t in sw.items():
        last = by_t.get(T_last)
        rows.append([integ, s] + [num(by_t[T]["error_m"], 2) if T in by_t else "—" for T in times]
                    + [num(max(float(by_t[T]["error_m"]) for T in by_t), 2),
                       last["status"] if last else "—", last["steps"] if last else "—",
                       num(last["cpu_seconds"]) if last else "—"])
    sections.append((
        "Error at each time and cost (runs.csv)",
        "Error: max over particles of |x − x_ref(t)| (m) of the state at t (a run with "
        "`run.t_max = t`); inf where the run did not reach t. Status, steps and CPU: the run to "
        "t = %s s.\n\n" % num(T_last)
        + md_table(["integrator", "setting"] + ["error at %s s (m)" % num(T) for T in times]
                   + ["largest error (m)", "status", "steps", "CPU to %s s (s)" % num(T_last)],
                   rows)))

    # Cheapest run per accuracy level at each time, and the runner-up among other integrators.
    rows = []
    for T in times:
        meas = [r for r in runs if r["measured"] == "yes" and float(r["time"]) == T
                and math.isfinite(float(r["error_m"]))]
        for level in LEVELS:
            ok = sorted((r for r in meas if float(r["error_m"]) <= level),
                        key=lambda r: float(r["cpu_seconds"]))
            if not ok:
                rows.append([num(T), num(level, exp=True), "none", "—", "—", "—", "—"])
                continue
            best = ok[0]
            other = [r for r in ok if r["integrator"] != best["integrator"]]
            rows.append([num(T), num(level, exp=True), "%s (%s)" % (best["integrator"],
                                                                     setting(best)),
                         num(best["cpu_seconds"]),
                         "%s (%s)" % (other[0]["integrator"], setting(other[0])) if other else "—",
                         num(other[0]["cpu_seconds"]) if other else "—",
                         num(float(other[0]["cpu_seconds"]) / float(best["cpu_seconds"])) + "×"
                         if other else "—"])
    sections.append((
        "Cheapest run per accuracy level (runs.csv)",
        "Per time t and error level: the measured run with error ≤ level at the least CPU to t, "
        "and the cheapest run of another integrator that meets the level.\n\n"
        + md_table(["t (s)", "error ≤ (m)", "cheapest", "CPU (s)", "runner-up (other integrator)",
                    "CPU (s)", "runner-up / cheapest"], rows)))

    rows = [[r["integrator"], num(r["time"]), num(r["dt"]), r["steps"], num(r["cpu_seconds"]),
             r["measured"]] for r in runs if r["status"] == "extrapolated"]
    sections.append((
        "Explicit methods, extrapolated (runs.csv)",
        "Stability-bound steps: a capped run from the start gives the CPU per step and the mean "
        "step; cost to t = CPU per step × t / mean step. Not measured to t.\n\n"
        + md_table(["integrator", "t (s)", "mean step (s)", "steps to t", "CPU to t (s)", "how"],
                   rows) if rows else ""))
    skipped = [r for r in runs if r["measured"].startswith("skipped")]
    if skipped:
        sections.append(("Skipped (runs.csv)", md_table(
            ["integrator", "setting", "t (s)", "why"],
            [[r["integrator"], setting(r), num(r["time"]), r["measured"]] for r in skipped])))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return "transient: tables", ["runs.csv", "references.csv", "manifest.json"], sections


def main(argv=None):
    return summary_main("transient", build, argv)


if __name__ == "__main__":
    main()
