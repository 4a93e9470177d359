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


def fnum(r, key):
    """float of a CSV field; nan when empty or absent (rows of an older runs.csv)."""
    v = r.get(key) or "nan"
    return float(v)


def crossings(r):
    """Designed crossings changed, '—' when not measured (empty, or -1: a diverged run)."""
    v = r.get("crossings_changed") or ""
    return v if v and int(v) >= 0 else "—"


def loosest_first(r):
    """Sort key: largest dt, loosest rtol or position_tol first."""
    if by_position_tol(r):
        return -fnum(r, "position_tol")
    return -(fnum(r, "dt") or fnum(r, "rtol"))


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
                ["scene", "integrator", "rtol (or dt)", "atol", "equilibrium_tol", "status",
                 "residual",
                 "Newton correction (m)", "its round-off floor (m)", "t_final (s)", "CPU (s)"],
                [[r["scene"], r["integrator"],
                  setting(r) if fnum(r, "dt") > 0 else num(r["rtol"], exp=True),
                  "—" if fnum(r, "dt") > 0 else num(r["atol"], exp=True),
                  num(r["equilibrium_tol"], exp=True), r["status"], num(r["residual"], 2),
                  num(r.get("newton_step_m", "nan"), 2), num(r.get("newton_floor_m", "nan"), 2),
                  num(r["t_final"]), num(r["cpu_seconds"])] for r in refs])))

    if best:
        rows = []
        for r in best:
            shape = r.get("error_measure") == "shape_err_m"
            level = num(r["error_level_m"], exp=True) + (" (shape)" if shape else "")
            if r["best"] == "none":
                rows.append([r["scene"], level, "none", "—", "—", "—", "—", "—"])
                continue
            err = num(r["pos_err_m"], 2)
            if shape:
                err = "%s (shape %s)" % (err, num(r["shape_err_m"], 2))
            rows.append([r["scene"], level, r["best"], setting(r),
                         num(r["cpu_seconds"]), err, r["runner_up"] or "—",
                         "%.2f" % float(r["runner_up_cpu_ratio"]) if r["runner_up"] else "—"])
        sections.append((
            "Cheapest run per accuracy level (best.csv)",
            "The cheapest measured run that settled within the error level (max position error, "
            "m; marked (shape): the shape error, max position error after the best in-plane "
            "rigid fit), and the next integrator's cheapest such run as a CPU ratio.\n\n"
            + md_table(["scene", "error level (m)", "cheapest", "setting", "CPU (s)",
                        "position error (m)", "runner-up", "runner-up CPU / cheapest"], rows)))

    shape_scenes = {r["scene"] for r in best if r.get("error_measure") == "shape_err_m"}
    for scene in scenes:
        sr = [r for r in measured if r["scene"] == scene]
        ok = [r for r in sr if settled(r)]
        if not sr:
            continue
        err_key = "shape_err_m" if scene in shape_scenes else "pos_err_m"
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
                         span([r[err_key] for r in iok], lambda v: num(v, 2)),
                         "; ".join(others) or "—"])
        cpu_note = ""
        if scene.startswith("knit"):
            cpu_note = (" CPU: the integrator's, the run's less the yarn clearance measuring "
                        "`knitsim knit` does inside it (runs.csv run_cpu_seconds, "
                        "clearance_cpu_seconds)." if sr[0].get("run_cpu_seconds") else
                        " CPU: the run's, the yarn clearance measuring `knitsim knit` does "
                        "inside it included (this runs.csv predates the driver's subtracting "
                        "it, as experiments/transient does).")
        shape_note = (" Shape error = the position error after the best in-plane rigid fit "
                      "(rotation about z, translation); this scene's errors are of the shape."
                      if err_key == "shape_err_m" else "")
        text = ("Measured runs only. Settled = status `equilibrium`; position error = max over "
                "particles of |x - x_ref| at the end." + shape_note + cpu_note + "\n\n" +
                md_table(["integrator", "settled", "CPU of the settled runs (s)",
                          "cheapest settled", "its CPU (s)", "its steps",
                          "× the scene's cheapest", "%s error of the settled runs (m)"
                          % ("shape" if err_key == "shape_err_m" else "position"),
                          "runs that did not settle"], rows))
        far = [r for r in ok if float(r[err_key]) > FAR]
        near = [r for r in ok if float(r[err_key]) <= FAR]
        if far:
            text += ("\nSettled on another equilibrium (more than %s m from the reference): %s.\n"
                     % (num(FAR), ", ".join("%s %s (%s m)" % (r["integrator"], setting(r),
                                                               num(r[err_key], 2))
                                            for r in far)))
        if near:
            coeff = [r["coeff_err_pct"] for r in near
                     if math.isfinite(float(r["coeff_err_pct"]))]
            text += ("\nAll %ssettled %s runs: %s error %s m%s.\n"
                     % ("other " if far else "", scene,
                        "shape" if err_key == "shape_err_m" else "position",
                        span([r[err_key] for r in near], lambda v: num(v, 2)),
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

    for scene in sorted(shape_scenes):
        sr = [r for r in measured if r["scene"] == scene]
        ref = [r for r in refs if r["scene"] == scene]
        picked = []
        for integ in dict.fromkeys(r["integrator"] for r in sr):
            picked += sorted((r for r in sr if r["integrator"] == integ), key=loosest_first)[:2]
        rows = [["%s (reference)" % r["integrator"] if r in ref else r["integrator"], setting(r),
                 r["status"], num(r["t_final"]), r["steps"],
                 "0" if r in ref else num(r["shape_err_m"], 2),
                 "0" if r in ref else num(r["rotation_deg"], 3),
                 num(r["clearance_min_r"], 4), num(r["clearance_end_r"], 4),
                 crossings(r), r["pairs_in_contact"] or "—",
                 r["renewals_cut"] or "—"] for r in ref + picked]
        low = min(sr, key=lambda r: fnum(r, "clearance_min_r"), default=None)
        crossed = [r for r in sr if crossings(r) not in ("—", "0")]
        sections.append((
            "%s: where each method lands at its extremes (runs.csv, references.csv)" % scene,
            "Per integrator its two loosest measured settings (largest dt, loosest rtol or "
            "position_tol), against the reference: status, the end state's shape error and "
            "in-plane rotation, the centrelines' clearance (minimum over the run, at the end; "
            "in r, the loop radius), designed crossings changed at the end, and the contact's "
            "pairs in contact and cut renewals.\n\n" + md_table(
                ["integrator", "setting", "status", "t_final (s)", "steps", "shape error (m)",
                 "in-plane rotation (°)", "min clearance (r)", "end clearance (r)",
                 "crossings changed", "pairs in contact", "renewals cut"], rows) +
            "\nOver all %d measured %s runs: lowest min clearance %s r (%s %s, %s); %d with a "
            "designed crossing changed (diverged runs measure neither).\n" % (
                len(sr), scene, num(low["clearance_min_r"], 4) if low else "—",
                low["integrator"] if low else "—", setting(low) if low else "—",
                low["status"] if low else "—", len(crossed))))

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
        yarn = scene in shape_scenes   # the knit columns of the scenes that have them
        rows = [[r["integrator"], setting(r), r["status"], num(r["t_final"]), r["steps"],
                 r["rhs_evals"], r["lin_setups"], num(r["cpu_seconds"]), num(r["residual"], 2),
                 num(r["pos_err_m"], 2)] +
                ([num(r["shape_err_m"], 2), num(r["rotation_deg"], 3),
                  num(r["clearance_min_r"], 4), crossings(r)] if yarn else
                 [num(r["coeff_err_pct"], 2)]) for r in sr]
        sections.append((
            "%s: every measured run (runs.csv)" % scene,
            md_table(["integrator", "setting", "status", "t_final (s)", "steps", "RHS evaluations",
                      "set-ups", "CPU (s)", "residual", "position error (m)"] +
                     (["shape error (m)", "in-plane rotation (°)", "min clearance (r)",
                       "crossings changed"] if yarn else ["Eq. 5 coefficient error (%)"]),
                     rows)))
    text = provenance(manifest)
    for scene, m in (manifest.get("scene_runs") or {}).items():
        build = m.get("knitsim_build") or {}
        la = m.get("load_average") or []
        text += ("- %s re-run alone: `%s`, knitsim build commit %s (%s), repository HEAD %s, "
                 "written (UTC) %s, %s cores, load average %s, wall cap %s s\n"
                 % (scene, m.get("command"), build.get("git_commit"), build.get("build_type"),
                    m.get("git_commit"), m.get("created_utc"), m.get("nproc"),
                    " / ".join("%.2f" % v for v in la), m.get("wall_cap_s")))
    sections.append(("Provenance", text))
    return ("work_precision: tables", ["runs.csv", "best.csv", "references.csv", "manifest.json"],
            sections)


def main(argv=None):
    return summary_main("work_precision", build, argv)


if __name__ == "__main__":
    main()
