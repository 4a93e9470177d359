#!/usr/bin/python3
"""Tables of experiments/peer from its CSV files only (compare.csv, runs.csv, manifest.json) ->
summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/peer/results)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, median, num, provenance, read_json, read_rows,  # noqa: E402
                    summary_main)


def groups(runs):
    """runs.csv's repeats as groups: a group starts where `repeat` restarts at 1."""
    out = []
    for r in runs:
        if r["repeat"] == "1" or not out:
            out.append([])
        out[-1].append(r)
    return out


def build(out):
    compare = read_rows(out, "compare.csv")
    runs = read_rows(out, "runs.csv")
    sections = []
    rows = []
    for c in compare:
        rows.append([c["scene"], "%s (%s dof)" % (c["knitsim_model"], c["knitsim_dof"]),
                     "%s / %s" % (num(c["knitsim_rtol"], exp=True),
                                  num(c["knitsim_atol"], exp=True)),
                     c["knitsim_status"], num(c["knitsim_cpu_median"]),
                     "%s (%s steps, t %s s)" % (num(c["scipy_cpu"]), c["scipy_steps"],
                                                num(c["scipy_t_final"])),
                     "**%s×**" % num(c["cpu_ratio"]), num(c["max_position_difference_m"], 2),
                     "%.4f / %.4f" % (-100 * float(c["centre_z_knitsim"]),
                                      -100 * float(c["centre_z_scipy"])),
                     "%.2f %%" % (100 * float(c["scipy_max_strain"]))])
    scipy_tol = ", ".join(sorted({"%s / %s" % (num(c["scipy_rtol"], exp=True),
                                               num(c["scipy_atol"], exp=True)) for c in compare}))
    sections.append((
        "knitsim against the scipy peer (compare.csv)",
        "CPU seconds per drape to equilibrium, medians of the repeats (knitsim: the solver's own "
        "`cpu_seconds`; scipy: `time.process_time()` around `solve_ivp`, at rtol / atol %s); "
        "ratio = scipy CPU / knitsim CPU; position difference = max over particles of "
        "|x_knitsim - x_scipy|; a reduced model (eighth, half) is unfolded first.\n\n" % scipy_tol
        + md_table(["scene", "knitsim model", "knitsim rtol / atol", "knitsim status",
                    "knitsim CPU (s)", "scipy BDF CPU (s)", "ratio", "max position difference (m)",
                    "centre sag knitsim / scipy (cm)", "scipy's largest strain"], rows)))

    rows = []
    for g in groups(runs):
        r0 = g[0]
        cpus = [float(r["cpu_seconds"]) for r in g]
        med = median(cpus)
        pick = min(g, key=lambda r: abs(float(r["cpu_seconds"]) - med))
        model = "full"
        if r0["tool"].startswith("knitsim"):
            for c in compare:
                if c["scene"] == r0["scene"] and float(c["knitsim_rtol"]) == float(r0["rtol"]) \
                        and abs(float(c["knitsim_cpu_median"]) - med) <= 1e-12 * max(1.0, med):
                    model = c["knitsim_model"]
        rows.append([r0["scene"], r0["tool"], model, num(r0["rtol"], exp=True),
                     "/".join(sorted(set(r["status"] for r in g))), pick["steps"],
                     num(pick["t_final"]), " / ".join(num(x) for x in cpus), num(med),
                     "%.3g" % (1000 * float(pick["cpu_seconds"]) / int(pick["steps"]))])
    sections.append((
        "Every run and the cost per step (runs.csv)",
        "One row per tool, scene, model and tolerance; CPU of each repeat in run order, their "
        "median, and CPU per step of the median run.\n\n"
        + md_table(["scene", "tool", "model", "rtol", "status", "steps", "t_final (s)",
                    "CPU of the repeats (s)", "median (s)", "ms per step"], rows)))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return "peer: tables", ["compare.csv", "runs.csv", "manifest.json"], sections


def main(argv=None):
    return summary_main("peer", build, argv)


if __name__ == "__main__":
    main()
