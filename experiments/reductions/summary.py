#!/usr/bin/python3
"""Tables of experiments/reductions from its CSV files only (state.csv, topology.csv, stop.csv,
static.csv, symmetry.csv, fits.csv, manifest.json) -> summary.md; the README points at them.
Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/reductions/results)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, num, provenance, read_json, read_rows, span,  # noqa: E402
                    summary_main)


def ratio(x):
    return "%.3g×" % float(x)


def build(out):
    state, topo = read_rows(out, "state.csv"), read_rows(out, "topology.csv")
    stop, static = read_rows(out, "stop.csv"), read_rows(out, "static.csv")
    sym, fits = read_rows(out, "symmetry.csv"), read_rows(out, "fits.csv")
    sections = []

    if state:
        sections.append((
            "1. Pinned particles out of the state (state.csv)",
            md_table(["scene", "particles", "pinned", "dof in the state",
                      "dof if the pins were state", "saved"],
                     [[r["scene"], r["particles"], r["pinned"], r["dof_in_state"],
                       r["dof_if_pins_were_state"], "%.1f %%" % (100 * float(r["saved_fraction"]))]
                      for r in state])))
    if topo:
        a = next((r for r in topo if r["topology"] == "a"), topo[0])
        rows = [[r["topology"], r["springs"], "%.3g" % float(r["euler_us_per_step"]),
                 "%.3f" % (float(r["euler_us_per_step"]) / float(a["euler_us_per_step"])),
                 r["bdf_status"], r["bdf_steps"], num(r["bdf_t_final"]),
                 num(r["bdf_cpu_seconds"])] for r in topo]
        sections.append((
            "2. Springs of the chosen topology only (topology.csv)",
            "four_corner: one explicit Euler step (one RHS evaluation) per topology, and a "
            "cvode-bdf drape to equilibrium (different physics per topology).\n\n" + md_table(
                ["topology", "springs", "µs per Euler step", "relative to topology %s"
                 % a["topology"], "cvode-bdf status", "steps", "t_final (s)", "CPU (s)"], rows)))
    if stop:
        rows = [[r["scene"], r["stop"], num(r["t_final"]), r["steps"], num(r["residual"], 2),
                 num(r["cpu_seconds"]), ratio(r["cpu_ratio"]),
                 num(r["max_position_difference_m"], 2)] for r in stop]
        sections.append((
            "3. Stop at equilibrium against a fixed end time (stop.csv)",
            "cvode-bdf; CPU relative to the equilibrium stop of the same scene; position "
            "difference to that run's state.\n\n" + md_table(
                ["scene", "stop", "t_final (s)", "steps", "residual", "CPU (s)",
                 "CPU / equilibrium stop", "max position difference (m)"], rows)))
    if static:
        rows = []
        for r in static:
            base = next((b for b in static if b["scene"] == r["scene"]
                         and b["integrator"] != "static"), None)
            rows.append([r["scene"], r["integrator"], r["status"], num(r["t_final"]), r["steps"],
                         num(r["residual"], 2),
                         ("%.3g×" % (float(base["residual"]) / float(r["residual"])))
                         if base and r is not base else "—",
                         num(r["cpu_seconds"]), ratio(r["cpu_ratio"]),
                         num(r["max_position_difference_m"], 2)])
        sections.append((
            "4. The `static` Newton polish after the dynamics (static.csv)",
            md_table(["scene", "integrator", "status", "t_final (s)", "steps", "residual",
                      "residual smaller by", "CPU (s)", "CPU / cvode-bdf",
                      "max position difference (m)"], rows)))
    if sym:
        rows = []
        for r in sym:
            full = next((f for f in sym if f["scene"] == r["scene"] and f["n"] == r["n"]
                         and f["integrator"] == r["integrator"] and f["model"] == "full"), None)
            rows.append([r["scene"], r["n"], r["integrator"], r["model"], r["dof"],
                         "%.3g" % (int(full["dof"]) / int(r["dof"])) if full else "—",
                         r["status"], r["steps"], r["factorisations"], num(r["cpu_seconds"]),
                         "%.3g×" % float(r["speedup"]),
                         num(r["max_position_difference_m"], 2),
                         num(r["coefficient_error_percent"], 2)])
        sections.append((
            "5. Symmetry-reduced scenes (symmetry.csv)",
            "Full grid, half (two_corner), quarter and eighth (four_corner) in turn; CPU = median "
            "of the repeats of the solver's own `cpu_seconds`; speed-up = full CPU / reduced "
            "CPU; the reduced equilibrium unfolded and compared with the full one (position, "
            "and the Eq. 5 error of its edge coefficients).\n\n" + md_table(
                ["scene", "n", "integrator", "model", "dof", "fewer dof than full", "status",
                 "steps", "factorisations", "CPU (s)", "speed-up", "max position difference (m)",
                 "Eq. 5 coefficient error (%)"], rows)))
    if fits:
        agg = []
        per = []
        for scene in dict.fromkeys(r["scene"] for r in fits):
            full = {r["sample"]: r for r in fits if r["scene"] == scene and r["model"] == "full"}
            red = {r["sample"]: r for r in fits if r["scene"] == scene and r["model"] != "full"}
            samples = [s for s in full if s in red]
            if not samples:
                continue
            model = red[samples[0]]["model"]
            for s in samples:
                f, r = full[s], red[s]
                per.append([s, scene, model, "%.8g" % float(f["objective"]),
                            "%.8g" % float(r["objective"]),
                            num(r["objective_relative_difference"], 2),
                            "yes" if r["same_country"] == "True" else "no",
                            "%s / %s" % (f["evaluations"], r["evaluations"]),
                            "%s / %s" % (f["failed_evaluations"], r["failed_evaluations"]),
                            "%.2f / %.2f" % (float(f["cpu_seconds"]), float(r["cpu_seconds"])),
                            "%.2f×" % float(r["speedup"])])
            lower = sum(float(red[s]["objective"]) < float(full[s]["objective"]) for s in samples)
            higher = sum(float(red[s]["objective"]) > float(full[s]["objective"]) for s in samples)
            agg.append([scene, model, "%d of %d" % (sum(red[s]["same_country"] == "True"
                                                         for s in samples), len(samples)),
                        span([red[s]["objective_relative_difference"] for s in samples],
                             lambda v: num(v, 2)),
                        "%d / %d" % (lower, higher),
                        span([full[s]["evaluations"] for s in samples]) + " / "
                        + span([red[s]["evaluations"] for s in samples]),
                        span([full[s]["failed_evaluations"] for s in samples]) + " / "
                        + span([red[s]["failed_evaluations"] for s in samples]),
                        span([full[s]["cpu_seconds"] for s in samples], lambda v: "%.2f" % v)
                        + " / " + span([red[s]["cpu_seconds"] for s in samples],
                                       lambda v: "%.2f" % v),
                        span([red[s]["speedup"] for s in samples], lambda v: "%.2f×" % v)])
        sections.append((
            "6. Fits on the reduced scene (fits.csv)",
            "`knitsim fit` on the full grid and on the reduction, one run each per twin sample; "
            "\"same country\" = the same best parameters; full / reduced in the paired "
            "columns.\n\n" + md_table(
                ["scene", "reduced model", "same best country", "objective relative difference",
                 "reduced lower / higher", "evaluations", "failed evaluations", "CPU (s)",
                 "speed-up"], agg)
            + "\nPer sample:\n\n" + md_table(
                ["sample", "scene", "reduced model", "objective full", "objective reduced",
                 "relative difference", "same country", "evaluations", "failed", "CPU (s)",
                 "speed-up"], per)))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return ("reductions: tables",
            ["state.csv", "topology.csv", "stop.csv", "static.csv", "symmetry.csv", "fits.csv",
             "manifest.json"], sections)


def main(argv=None):
    return summary_main("reductions", build, argv)


if __name__ == "__main__":
    main()
