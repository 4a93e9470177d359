#!/usr/bin/python3
"""Tables of experiments/work_precision from its CSV files only (runs.csv, best.csv,
references.csv, manifest.json) -> summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/work_precision/results)
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, num, provenance, read_json, read_rows, span,  # noqa: E402
                    summary_main)


FAR = 1e-3  # m: a settled run farther than this from the reference found another equilibrium


def by_position_tol(r):
    return math.isfinite(float(r.get("position_tol") or "nan"))


def setting(r):
    """'rtol 1e-6' for an adaptive run, 'dt 100 s' for a fixed-step one, 'position_tol 1e-8 m'
    for the equilibrium solver."""
    if by_position_tol(r):
        return "position_tol %s m" % num(r["position_tol"], exp=True)
    if float(r.get("dt") or 0) > 0:
        return "dt %s s" % num(r["dt"], 4)
    return "rtol %s" % num(r["rtol"], exp=True)


def settled(r):
    return r["status"] == "equilibrium"


def build(out):
    runs = read_rows(out, "runs.csv")
    best = read_rows(out, "best.csv")
    refs = read_rows(out, "references.csv")
    manifest = read_json(out, "manifest.json")
    sections = []
    scenes = list(dict.fromkeys(r["scene"] for r in runs))
    measured = [r for r in runs if r["measured"] == "yes"]

    if refs:
        sections.append((
            "References (references.csv)",
            "Per scene, the run every error is measured against; its Newton correction at the "
            "end estimates its own distance to the minimum, and the correction's round-off floor "
            "bounds what any stop can resolve.\n\n" + md_table(
                ["scene", "integrator", "rtol", "atol", "equilibrium_tol", "status", "residual",
                 "Newton correction (m)", "its round-off floor (m)", "t_final (s)", "CPU (s)"],
                [[r["scene"], r["integrator"], num(r["rtol"], exp=True), num(r["atol"], exp=True),
                  num(r["equilibrium_tol"], exp=True), r["status"], num(r["residual"], 2),
                  num(r.get("newton_step_m", "nan"), 2), num(r.get("newton_floor_m", "nan"), 2),
                  num(r["t_final"]), num(r["cpu_seconds"])] for r in refs])))

    if best:
        rows = []
        for r in best:
            if r["best"] == "none":
                rows.append([r["scene"], num(r["error_level_m"], exp=True), "none", "—", "—",
                             "—", "—", "—"])
                continue
            rows.append([r["scene"], num(r["error_level_m"], exp=True), r["best"], setting(r),
                         num(r["cpu_seconds"]), num(r["pos_err_m"], 2), r["runner_up"] or "—",
                         "%.2f" % float(r["runner_up_cpu_ratio"]) if r["runner_up_cpu_ratio"]
                         else "—"])
        sections.append((
            "Cheapest run per accuracy level (best.csv)",
            "The cheapest measured run that settled within the error level (max position error, "
            "m), and the next integrator's cheapest such run as a CPU ratio.\n\n" + md_table(
                ["scene", "error level (m)", "cheapest", "setting", "CPU (s)", "position error (m)",
                 "runner-up", "runner-up CPU / cheapest"], rows)))

    for scene in scenes:
        sr = [r for r in measured if r["scene"] == scene]
        ok = [r for r in sr if settled(r)]
        if not sr:
            continue
        cheapest = min((float(r["cpu_seconds"]) for r in ok), default=math.nan)
        rows = []
        for integ in dict.fromkeys(r["integrator"] for r in sr):
            ir = [r for r in sr if r["integrator"] == integ]
            iok = [r for r in ir if settled(r)]
            c = min(iok, key=lambda r: float(r["cpu_seconds"])) if iok else None
            others = ["%s: %s" % (setting(r).split(" ", 1)[1], r["status"])
                      for r in ir if not settled(r)]
            rows.append([integ, "%d of %d" % (len(iok), len(ir)),
                         span([r["cpu_seconds"] for r in iok]),
                         setting(c) if c else "—", num(c["cpu_seconds"]) if c else "—",
                         c["steps"] if c else "—",
                         "%.3g" % (float(c["cpu_seconds"]) / cheapest) if c else "—",
                         span([r["pos_err_m"] for r in iok], lambda v: num(v, 2)),
                         "; ".join(others) or "—"])
        cpu_note = ""
        if scene == "knit":
            cpu_note = (" CPU: the integrator's, the run's less the yarn clearance measuring "
                        "`knitsim knit` does inside it (runs.csv run_cpu_seconds, "
                        "clearance_cpu_seconds)." if "run_cpu_seconds" in sr[0] else
                        " CPU: the run's, the yarn clearance measuring `knitsim knit` does "
                        "inside it included (this runs.csv predates the driver's subtracting "
                        "it, as experiments/transient does).")
        text = ("Measured runs only. Settled = status `equilibrium`; position error = max over "
                "particles of |x - x_ref| at the end." + cpu_note + "\n\n" + md_table(
                    ["integrator", "settled", "CPU of the settled runs (s)", "cheapest settled",
                     "its CPU (s)", "its steps", "× the scene's cheapest", "position error of "
                     "the settled runs (m)", "runs that did not settle"], rows))
        far = [r for r in ok if float(r["pos_err_m"]) > FAR]
        near = [r for r in ok if float(r["pos_err_m"]) <= FAR]
        if far:
            text += ("\nSettled on another equilibrium (more than %s m from the reference): %s.\n"
                     % (num(FAR), ", ".join("%s %s (%s m)" % (r["integrator"], setting(r),
                                                               num(r["pos_err_m"], 2))
                                            for r in far)))
        if near:
            coeff = [r["coeff_err_pct"] for r in near
                     if math.isfinite(float(r["coeff_err_pct"]))]
            text += ("\nAll %ssettled %s runs: position error %s m%s.\n"
                     % ("other " if far else "", scene,
                        span([r["pos_err_m"] for r in near], lambda v: num(v, 2)),
                        "; Eq. 5 coefficient error %s %%" % span(coeff, lambda v: num(v, 2))
                        if coeff else ""))
        adaptive = [r for r in sr if float(r["dt"] or 0) == 0 and not by_position_tol(r)]
        if adaptive:
            integs = list(dict.fromkeys(r["integrator"] for r in adaptive))
            rtols = sorted({float(r["rtol"]) for r in adaptive}, reverse=True)
            cell = {(r["integrator"], float(r["rtol"])): r for r in adaptive}
            prow = []
            for rt in rtols:
                row = [num(rt, exp=True)]
                for i in integs:
                    r = cell.get((i, rt))
                    row.append("—" if r is None else num(r["cpu_seconds"]) +
                               ("" if settled(r) else " (%s)" % r["status"]))
                prow.append(row)
            text += ("\nCPU seconds of the adaptive integrators by rtol (status in brackets when "
                     "the run did not settle):\n\n" + md_table(["rtol"] + integs, prow))
        sections.append(("%s: per integrator (runs.csv)" % scene, text))

    ext = [r for r in runs if r["status"] == "extrapolated"]
    if ext:
        rows = [[r["scene"], r["integrator"], num(r["dt"]), num(r["t_final"], 4),
                 num(r["steps"], 2), num(1e6 * float(r["cpu_per_step"])),
                 num(r["cpu_seconds"], 2), r["measured"].replace("extrapolated: ", "")]
                for r in ext]
        sections.append((
            "Explicit methods on the drapes, extrapolated (runs.csv)",
            "Not run to the end: CPU = CPU per step (from a capped run) × t_settle / dt.\n\n"
            + md_table(["scene", "integrator", "dt (s)", "t_settle (s)", "steps", "µs per step",
                        "estimated CPU (s)", "from"], rows)))

    for scene in scenes:
        sr = [r for r in measured if r["scene"] == scene]
        rows = [[r["integrator"], setting(r), r["status"], num(r["t_final"]), r["steps"],
                 r["rhs_evals"], r["lin_setups"], num(r["cpu_seconds"]), num(r["residual"], 2),
                 num(r["pos_err_m"], 2), num(r["coeff_err_pct"], 2)] for r in sr]
        sections.append((
            "%s: every measured run (runs.csv)" % scene,
            md_table(["integrator", "setting", "status", "t_final (s)", "steps", "RHS evaluations",
                      "set-ups", "CPU (s)", "residual", "position error (m)",
                      "Eq. 5 coefficient error (%)"], rows)))
    sections.append(("Provenance", provenance(manifest)))
    return ("work_precision: tables", ["runs.csv", "best.csv", "references.csv", "manifest.json"],
            sections)


def main(argv=None):
    return summary_main("work_precision", build, argv)


if __name__ == "__main__":
    main()
