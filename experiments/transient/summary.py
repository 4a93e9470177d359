#!/usr/bin/python3
"""Tables of experiments/transient from its CSV files only (runs.csv, references.csv,
ringing.csv, manifest.json) -> summary.md; the README points at them. Standard library only.
One set of tables per case (runs.csv's `scene`): two_corner_slack (times in s, errors in m) and
single_tuck, the knit tuck's ringing (times in us, errors in loop radii r and m).

    summary.py [DIR] [--output FILE]     (default DIR: experiments/transient/results)
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import md_table, num, provenance, read_json, read_rows, summary_main  # noqa: E402

# Per case: how times and errors are shown and the accuracy levels of the "cheapest" table.
# The drape's errors are in m (levels 1e-2 ... 1e-8 m); the knit's in loop radii r
# (r = 8.9e-5 m: 1e-2 ... 1e-8 r is 8.9e-7 ... 8.9e-13 m).
SHOW = {
    "two_corner_slack": dict(title="two_corner_slack (drape)", t_scale=1.0, t_unit="s",
                             err="error_m", err_unit="m", levels=[1e-2, 1e-4, 1e-6, 1e-8]),
    "single_tuck": dict(title="single_tuck (knit tuck's ringing)", t_scale=1e6, t_unit="us",
                        err="error_over_r", err_unit="r", levels=[1e-2, 1e-4, 1e-6, 1e-8]),
}
DEFAULT_SHOW = dict(t_scale=1.0, t_unit="s", err="error_m", err_unit="m",
                    levels=[1e-2, 1e-4, 1e-6, 1e-8])


def adaptive(r):
    return float(r["rtol"]) > 0


def own_velocity_atol(r):
    """An adaptive run with a velocity tolerance other than its atol (the knit command's own)."""
    return adaptive(r) and r.get("velocity_atol", "") not in ("", r["atol"]) and \
        float(r["velocity_atol"]) != float(r["atol"])


def sweep_name(r):
    """The line a run belongs to: its integrator, and the velocity tolerance if it is not atol."""
    return r["integrator"] + (" (velocity atol %s m/s)" % num(r["velocity_atol"], exp=True)
                              if own_velocity_atol(r) else "")


def setting(r):
    if adaptive(r):
        return "rtol %s" % num(r["rtol"], exp=True)
    auto = r.get("dt_given", "") != "" and float(r["dt_given"]) == 0
    return "dt %s s%s" % (num(r["dt"]), " (automatic)" if auto else "")


def sweeps(runs):
    """{(sweep name, setting): {time: row}} of the measured runs."""
    out = {}
    for r in runs:
        if r["measured"] == "yes":
            out.setdefault((sweep_name(r), setting(r)), {})[float(r["time"])] = r
    return out


def case_sections(case, runs, refs, ringing):
    sh = dict(DEFAULT_SHOW, title=case)
    sh.update(SHOW.get(case, {}))
    title, err, eu = sh["title"], sh["err"], sh["err_unit"]

    def t(x):
        return num(float(x) * sh["t_scale"])

    tu = sh["t_unit"]
    times = sorted({float(r["time"]) for r in runs})
    sections = []
    has_tight = any(r.get("tight_distance_m", "") not in ("", "nan") for r in refs)
    sections.append(("%s: references (references.csv)" % title, md_table(
        ["t (%s)" % tu, "integrator", "rtol / atol", "status", "steps", "CPU (s)",
         "distance to the rtol %s run (m)" % (num(refs[0]["check_rtol"], exp=True) if refs else "")]
        + (["distance to the rtol %s run (m)" % num(refs[0]["tight_rtol"], exp=True)]
           if has_tight else []),
        [[t(r["time"]), r["integrator"], "%s / %s" % (num(r["rtol"], exp=True),
                                                      num(r["atol"], exp=True)),
          r["status"], r["steps"], num(r["cpu_seconds"]), num(r["check_distance_m"], 2)]
         + ([num(r["tight_distance_m"], 2)] if has_tight else [])
         for r in refs])))

    if ringing:
        sections.append((
            "%s: the reference's time scale (ringing.csv)" % title,
            "cvode-bdf at rtol %s (velocity atol = atol) to each t; distance to the settled state "
            "(the same run without t_max, at equilibrium at t = %s us); largest speed over the "
            "points; static residual (|net force| / (k_w r)).\n\n"
            % (num(ringing[0]["rtol"], exp=True), t(ringing[0]["settled_t"]))
            + md_table(["t (%s)" % tu, "largest displacement (r)", "distance to settled (r)",
                        "largest speed (m/s)", "residual"],
                       [[t(r["time"]), num(r["max_displacement_over_r"]),
                         num(r["distance_to_settled_over_r"], 2), num(r["max_speed_m_per_s"], 2),
                         num(r["residual"], 2)] for r in ringing])))

    # Every setting: error at each time and the CPU of the run to the last one.
    sw = sweeps(runs)
    T_last = times[-1] if times else 0
    rows = []
    clearance = any(r.get("clearance_states", "") != "" for r in runs)
    for (name, s), by_t in sw.items():
        last = by_t.get(T_last)
        rows.append([name, s] + [num(by_t[T][err], 2) if T in by_t else "—" for T in times]
                    + [num(max(float(by_t[T][err]) for T in by_t), 2),
                       last["status"] if last else "—", last["steps"] if last else "—"]
                    + ([last["clearance_states"] if last else "—"] if clearance else [])
                    + [num(last["cpu_seconds"]) if last else "—"])
    sections.append((
        "%s: error at each time and cost (runs.csv)" % title,
        "Error: max over particles of |x − x_ref(t)| (%s) of the state at t (a run with "
        "`run.t_max = t`); inf where the run did not reach t. Status, steps and CPU: the run to "
        "t = %s %s%s.\n\n" % (eu, t(T_last), tu,
                               "; CPU: the integrator's, the run's less the yarn clearance "
                               "measuring `knitsim knit` does within it (clearance measurements: "
                               "their count; runs.csv run_cpu_seconds, clearance_cpu_seconds)"
                               if clearance else "")
        + md_table(["integrator", "setting"] + ["error at %s %s (%s)" % (t(T), tu, eu)
                                                for T in times]
                   + ["largest error (%s)" % eu, "status", "steps"]
                   + (["clearance measurements"] if clearance else [])
                   + ["CPU to %s %s (s)" % (t(T_last), tu)], rows)))

    # Error per unit rtol of the adaptive sweeps whose velocities share atol.
    rows = []
    for (name, s), by_t in sw.items():
        first = next(iter(by_t.values()))
        if not adaptive(first) or own_velocity_atol(first):
            continue
        rtol = float(first["rtol"])
        rows.append([name, s] + [num(float(by_t[T]["error_m"]) / rtol, 2) if T in by_t else "—"
                                 for T in times])
    if rows:
        sections.append((
            "%s: error / rtol of the adaptive methods (runs.csv)" % title,
            "Error (m) divided by rtol (atol = 10^-3 rtol on positions and velocities): the "
            "constant C of error ≈ C rtol.\n\n"
            + md_table(["integrator", "setting"] + ["error / rtol at %s %s (m)" % (t(T), tu)
                                                    for T in times], rows)))

    # Cheapest run per accuracy level at each time, and the runner-up among other integrators.
    rows = []
    for T in times:
        meas = [r for r in runs if r["measured"] == "yes" and float(r["time"]) == T
                and math.isfinite(float(r[err]))]
        for level in sh["levels"]:
            ok = sorted((r for r in meas if float(r[err]) <= level),
                        key=lambda r: float(r["cpu_seconds"]))
            if not ok:
                rows.append([t(T), num(level, exp=True), "none", "—", "—", "—", "—"])
                continue
            best = ok[0]
            other = [r for r in ok if r["integrator"] != best["integrator"]]
            rows.append([t(T), num(level, exp=True),
                         "%s (%s)" % (sweep_name(best), setting(best)),
                         num(best["cpu_seconds"]),
                         "%s (%s)" % (sweep_name(other[0]), setting(other[0])) if other else "—",
                         num(other[0]["cpu_seconds"]) if other else "—",
                         num(float(other[0]["cpu_seconds"]) / float(best["cpu_seconds"])) + "×"
                         if other else "—"])
    sections.append((
        "%s: cheapest run per accuracy level (runs.csv)" % title,
        "Per time t and error level: the measured run with error ≤ level at the least CPU to t, "
        "and the cheapest run of another integrator that meets the level.\n\n"
        + md_table(["t (%s)" % tu, "error ≤ (%s)" % eu, "cheapest", "CPU (s)",
                    "runner-up (other integrator)", "CPU (s)", "runner-up / cheapest"], rows)))

    rows = [[r["integrator"], t(r["time"]), num(r["dt"]), r["steps"], num(r["cpu_seconds"]),
             r["measured"]] for r in runs if r["status"] == "extrapolated"]
    if rows:
        sections.append((
            "%s: explicit methods, extrapolated (runs.csv)" % title,
            "Stability-bound steps: a capped run from the start gives the CPU per step and the "
            "mean step; cost to t = CPU per step × t / mean step. Not measured to t.\n\n"
            + md_table(["integrator", "t (%s)" % tu, "mean step (s)", "steps to t",
                        "CPU to t (s)", "how"], rows)))
    skipped = [r for r in runs if r["measured"].startswith("skipped")]
    if skipped:
        sections.append(("%s: skipped (runs.csv)" % title, md_table(
            ["integrator", "setting", "t (%s)" % tu, "why"],
            [[sweep_name(r), setting(r), t(r["time"]), r["measured"]] for r in skipped])))
    return sections


def build(out):
    runs = read_rows(out, "runs.csv")
    refs = read_rows(out, "references.csv")
    ringing = read_rows(out, "ringing.csv")
    cases = list(dict.fromkeys(r["scene"] for r in runs + refs))
    sections = []
    for case in cases:
        sections += case_sections(case, [r for r in runs if r["scene"] == case],
                                  [r for r in refs if r["scene"] == case],
                                  [r for r in ringing if r["scene"] == case])
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    sources = ["runs.csv", "references.csv"] + (["ringing.csv"] if ringing else []) + \
        ["manifest.json"]
    return "transient: tables", sources, sections


def main(argv=None):
    return summary_main("transient", build, argv)


if __name__ == "__main__":
    main()
