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
        model = r0.get("knitsim_model") or "full"
        if r0["tool"].startswith("knitsim") and not r0.get("knitsim_model"):
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
    sections.append(("The equilibrium solver against scipy's trust-region Newton (optimiser.csv)",
                     optimiser_table(read_rows(out, "optimiser.csv"))))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return "peer: tables", ["compare.csv", "optimiser.csv", "runs.csv", "manifest.json"], sections


def optimiser_table(rows):
    """Per scene and solver: CPU (median of the repeats), iterations, status, distance to the
    knitsim equilibrium solver's answer, and the ratios to the whole-sheet solver and to the
    default run; '' if the CSV is absent."""
    if not rows:
        return ""
    out = []
    for o in rows:
        k = float(o["knitsim_cpu"])
        d = float(o["default_cpu"])
        out.append([o["scene"], "knitsim equilibrium, whole sheet (%s dof)" % o["knitsim_dof"],
                    o["knitsim_certificate"], o["knitsim_steps"], "its stop", num(k), "1×",
                    num(k / d) + "×", "0"])
        out.append([o["scene"], "knitsim default run (equilibrium, model.symmetry = auto: %s dof)"
                    % o["default_dof"], o["default_certificate"], o["default_steps"], "its stop",
                    num(d),
                    num(d / k) + "×", "1×", num(o["default_distance_m"], 2)])
        for m in ("trust-exact", "trust-ncg"):
            if m + "_cpu" not in o:
                continue
            c = float(o[m + "_cpu"])
            out.append([o["scene"], "scipy minimize %s, whole sheet" % m, o[m + "_status"],
                        o[m + "_iterations"], num(o.get(m + "_newton_step_m"), 2), num(c),
                        "**%s×**" % num(c / k), num(c / d) + "×",
                        num(o[m + "_distance_m"], 2)])
        b = float(o["scipy_bdf_cpu"])
        out.append([o["scene"], "scipy solve_ivp BDF, whole sheet (table above)", "equilibrium",
                    "—", "—", num(b), "**%s×**" % num(b / k), num(b / d) + "×", "—"])
    fd = ", ".join("%s %s / %s" % (o["scene"], num(o["gradient_fd_error"], 2),
                                   num(o["hessian_fd_error"], 2)) for o in rows)
    return ("The same potential energy (springs + gravity, pins fixed) from the same flat state. "
            "knitsim: `knitsim drape --integrator equilibrium` (its `cpu_seconds`); scipy: "
            "`time.process_time()` around `minimize` with the analytic gradient and sparse "
            "Hessian (`drape_scipy.run_trust`), stopped by knitsim's test in positions (Newton "
            "correction ≤ 1e-10 m); set-up excluded on both sides. Steps: the solver's accepted "
            "and rejected steps (knitsim) or iterations (scipy). Ratios are CPU / CPU of the "
            "knitsim row named in the column; distance = max over particles of |x − x_knitsim| "
            "(m) to the whole-sheet knitsim answer; knitsim's stop: Newton correction ≤ 1e-10 m; "
            "status stalled: scipy accepted no step after a restart, short of that stop. Relative differences of the peer's gradient / "
            "Hessian to central finite differences: %s.\n\n" % fd
            + md_table(["scene", "solver", "status", "steps / iterations",
                        "Newton correction at the end (m)", "CPU (s)",
                        "× knitsim whole sheet", "× knitsim default run",
                        "distance to knitsim (m)"], out))


def main(argv=None):
    return summary_main("peer", build, argv)


if __name__ == "__main__":
    main()
