#!/usr/bin/python3
"""Tables of experiments/benchmark from its CSV files only -> summary.md; the README points at
them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/benchmark/results)

The benchmark has three drivers, each writing into its own folder; results/ keeps their files
under prefixes. Each section is written when its files are in DIR, under the committed name or
under the name the driver writes:
  run.sh        drape_summary.csv, drape_runs.csv, drape_manifest.json
                (run.sh: summary.csv, runs.csv, manifest.json)
  knit_atol.sh  knit_atol.csv (knit.csv): the velocity_atol sweep of the tucks40 chart;
                knit_atol_timed.csv, knit_cg_timed.csv (knit_timed.csv): timed repeats;
                knit_atol_drape.csv (drape.csv): velocity_atol on the drape scenes;
                knit_atol_manifest.json, knit_atol_timed_drape_manifest.json,
                knit_cg_timed_manifest.json (manifest.json)
  stops.sh      stops_LABEL_summary.csv, stops_LABEL.csv, stops_LABEL_manifest.json
                (stops.sh: summary.csv, stops.csv, manifest.json)
"""
import glob
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, num, provenance, read_json, read_rows, span,  # noqa: E402
                    summary_main)

# The design targets for one drape (docs/performance.md; the requirement, not a result).
TARGETS = (("four_corner ≤ 10 ms", "four_corner", 0.010),
           ("two_corner ≤ 0.5 s", "two_corner", 0.5))
EULER_FACTOR = 1e4  # target: >= 1e4 x faster than the paper's explicit Euler


def first(folder, names, column=None):
    """The first of `names` that exists in `folder` (and has `column`, if given)."""
    for n in names:
        rows = read_rows(folder, n)
        if rows and (column is None or column in rows[0]):
            return n, rows
    return None, []


def manifest_text(folder, names):
    for n in names:
        m = read_json(folder, n)
        if m:
            return "\n" + provenance(m, n)
    return ""


def drape_section(folder):
    name, summ = first(folder, ["drape_summary.csv", "summary.csv"], "scene")
    if not summ:
        return None
    runs_name = "drape_runs.csv" if name == "drape_summary.csv" else "runs.csv"
    runs = read_rows(folder, runs_name)
    base = next((r for r in summ if r["scene"] == "four_corner" and r["integrator"] == "cvode-bdf"),
                None)
    whole = {r["scene"]: r for r in summ if r["integrator"] == "cvode-bdf"
             and "/" not in r["scene"]}
    rows = []
    for r in summ:
        scene, _, part = r["scene"].partition("/")
        ref = whole.get(scene)
        label = scene + (", " + part if part and not part.startswith("dt") else "")
        integ = r["integrator"] + (", dt %s s" % part[2:-1] if part.startswith("dt") else "")
        rows.append([label, integ, r["runs"], r["status"], num(r["t_final"], 4),
                     num(r["steps"], 3), num(r["wall_seconds"]), num(r["cpu_seconds"]),
                     num(float(r["cpu_seconds"]) / float(ref["cpu_seconds"]))
                     if ref else "—",
                     r["measured"]])
    text = ("Medians of the runs (`wall_seconds` and `cpu_seconds`: the solver's own times from "
            "summary.json, set-up and file output excluded); the Euler row is extrapolated when "
            "`measured` says so.\n\n" + md_table(
                ["scene", "integrator", "runs", "status", "t_final (s)", "steps", "wall (s)",
                 "CPU (s)", "CPU / the scene's whole-sheet cvode-bdf", "measured"], rows))
    eu = next((r for r in runs if r["integrator"] == "euler" and r["repeat"] == "1"), None)
    probe = next((r for r in runs if r["integrator"] == "euler" and r["repeat"] == "probe"), None)
    verlet = next((r for r in runs if r["integrator"] == "verlet"), None)
    if eu:
        text += ("\nEuler: dt %s s%s, %s steps timed, %s µs CPU per step; t_settle %s."
                 % (num(eu["dt"], 3),
                    " (0.9 × the predicted limit %s s; the automatic step of the probe run is "
                    "half the limit)" % num(2 * float(probe["dt"]), 3) if probe else "",
                    eu["steps"], num(1e6 * float(eu["cpu_seconds"]) / int(eu["steps"]), 3),
                    "%s s from a verlet run (%s steps)" % (num(verlet["t_final"], 4),
                                                          verlet["steps"])
                    if verlet else "from the Euler run itself"))
    euler = next((r for r in summ if r["integrator"] == "euler"), None)
    checks = []
    for label, scene, limit in TARGETS:
        for r in summ:
            if r["scene"].partition("/")[0] != scene or r["integrator"] == "euler":
                continue
            settled = r["status"] == "equilibrium"
            ok = settled and float(r["cpu_seconds"]) <= limit
            checks.append([label, r["scene"], r["integrator"], num(r["cpu_seconds"]),
                           "met" if ok else ("not met" if settled else
                                             "no evidence (%s)" % r["status"])])
    if euler and base:
        ratio = float(euler["cpu_seconds"]) / float(base["cpu_seconds"])
        checks.append(["≥ %s× faster than Euler" % num(EULER_FACTOR), "four_corner",
                       "cvode-bdf", "Euler / cvode-bdf = %s" % num(ratio, 2),
                       "met" if ratio >= EULER_FACTOR else "not met"])
    if checks:
        text += ("\n\nDesign targets (docs/performance.md; CPU of one drape; a run that did not "
                 "settle is no evidence):\n\n" + md_table(["target", "scene", "integrator", "CPU (s)",
                                              "verdict"], checks))
    text += manifest_text(folder, ["drape_manifest.json"] if name == "drape_summary.csv"
                          else ["manifest.json"])
    return "Drape benchmark (%s, %s)" % (name, runs_name), text


def knit_sweep_section(folder):
    name, rows = first(folder, ["knit_atol.csv", "knit.csv"])
    if not rows:
        return None
    table = [[r["case"], r["integrator"], num(r["rtol"], exp=True), num(r["atol"], exp=True),
              num(r["velocity_atol"], exp=True) if float(r["velocity_atol"]) else "0 (= atol)",
              r["status"], r["steps"], r["lin_setups"], r["nonlin_iters"],
              num(r["cpu_seconds"]), num(r["shape_dx_over_r"], 2),
              num(r["dx_max_over_r"], 2)] for r in rows]
    sweep = [r for r in rows if r["case"] != "reference"]
    text = ("tucks40 chart, `knit.stabiliser=0.1`, one run each; shape dx / r = the largest point "
            "distance from the reference in loop radii after the best rigid motion; dx / r as "
            "written.\n\n" + md_table(
                ["case", "integrator", "rtol", "atol (m)", "velocity_atol (m/s)", "status",
                 "steps", "set-ups", "Newton its", "CPU (s)", "shape dx / r", "dx / r"], table))
    if sweep:
        text += ("\n%d of %d sweep runs reached equilibrium; their shape dx / r: %s.\n"
                 % (sum(r["status"] == "equilibrium" for r in sweep), len(sweep),
                    span([r["shape_dx_over_r"] for r in sweep if r["status"] == "equilibrium"],
                         lambda v: num(v, 2))))
    text += manifest_text(folder, ["knit_atol_manifest.json"] if name == "knit_atol.csv"
                          else ["manifest.json"])
    return "Knit chart: the velocity_atol sweep (%s)" % name, text


def knit_timed_sections(folder):
    out = []
    for name, man in (("knit_atol_timed.csv", "knit_atol_timed_drape_manifest.json"),
                      ("knit_cg_timed.csv", "knit_cg_timed_manifest.json"),
                      ("knit_timed.csv", "manifest.json")):
        rows = read_rows(folder, name)
        if not rows:
            continue
        solver = "newton_solver" in rows[0]
        fact = "factorisations" in rows[0]
        head = ["case", "integrator"] + (["Newton solver"] if solver else []) + \
            ["rtol", "atol", "velocity_atol", "runs", "status", "steps", "set-ups"] + \
            (["factorisations"] if fact else []) + ["CPU median (range), s", "shape dx / r"]
        table = []
        for r in rows:
            table.append([r["case"], r["integrator"]] + ([r["newton_solver"]] if solver else [])
                         + [num(r["rtol"], exp=True), num(r["atol"], exp=True),
                            num(r["velocity_atol"], exp=True) if float(r["velocity_atol"])
                            else "0", r["runs"], r["status"], r["steps"], r["lin_setups"]]
                         + ([r["factorisations"]] if fact else [])
                         + ["%s (%s–%s)" % (num(r["cpu_median"]), num(r["cpu_min"]),
                                            num(r["cpu_max"])), num(r["shape_dx_over_r"], 2)])
        text = ("tucks40 chart, `knit.stabiliser=0.1`, repeats run interleaved; CPU = "
                "`stats.cpu_seconds`.\n\n" + md_table(head, table)
                + manifest_text(folder, [man]))
        out.append(("Knit chart: timed repeats (%s)" % name, text))
    return out


def knit_drape_section(folder):
    name, rows = first(folder, ["knit_atol_drape.csv", "drape.csv"], "velocity_atol")
    if not rows:
        return None
    table = []
    for r in rows:
        v0 = next((b for b in rows if b["scene"] == r["scene"]
                   and float(b["velocity_atol"]) == 0), None)
        table.append([r["scene"], num(r["velocity_atol"], exp=True)
                      if float(r["velocity_atol"]) else "0", r["status"], r["steps"],
                      "%+.0f %%" % (100 * (int(r["steps"]) / int(v0["steps"]) - 1))
                      if v0 else "—",
                      r["lin_setups"], num(r["cpu_seconds"]), num(r["residual"], 2),
                      num(r["max_edge_relative_change"], 2)])
    text = ("cvode-bdf, rtol 1e-8 (as `knitsim fit`), atol 1e-9, one run each; edge change = the "
            "largest relative change of an edge's coefficient vector against velocity_atol "
            "0.\n\n" + md_table(["scene", "velocity_atol (m/s)", "status", "steps",
                                  "steps vs 0", "set-ups", "CPU (s)", "residual",
                                  "edge change"], table)
            + manifest_text(folder, ["knit_atol_timed_drape_manifest.json"]
                            if name == "knit_atol_drape.csv" else ["manifest.json"]))
    return "Drape scenes: velocity_atol (%s)" % name, text


def stops_sets(folder):
    """(label, summary rows, run rows, manifest) per stops.sh run in folder."""
    out = []
    for path in sorted(glob.glob(os.path.join(folder, "stops_*_summary.csv"))):
        label = os.path.basename(path)[len("stops_"):-len("_summary.csv")]
        out.append((label, read_rows(folder, os.path.basename(path)),
                    read_rows(folder, "stops_%s.csv" % label),
                    read_json(folder, "stops_%s_manifest.json" % label)))
    if not out:
        _, summ = first(folder, ["summary.csv"], "newton_solver")
        if summ:
            out.append(("", summ, read_rows(folder, "stops.csv"),
                        read_json(folder, "manifest.json")))
    return out


def option(command, flag, default):
    m = re.search(r"%s (\S+)" % re.escape(flag), command or "")
    return m.group(1) if m else default


def stops_section(folder):
    sets = stops_sets(folder)
    if not sets:
        return None
    kinds = [("cvode-bdf", "ldl"), ("cvode-bdf", "cg-ldl"), ("static", "cg-ldl")]
    table = []
    detail = []
    for label, summ, runs, man in sets:
        cmd = man.get("command", "")
        scene = option(cmd, "--scene", "two_corner")
        sym = option(cmd, "--symmetry", "none")
        by = {(r["integrator"], r["newton_solver"]): r for r in summ}
        row = [label or "—", scene + ("" if sym == "none" else ", " + sym),
               option(cmd, "--n", "30"), option(cmd, "--rtol", "1e-8"),
               option(cmd, "--seed", "5"), "`%s`" % man.get("knitsim", "?")]
        for k in kinds:
            r = by.get(k)
            row.append("—" if r is None else "%s of %s (%s s)" % (r["equilibrium"], r["runs"],
                                                                  num(r["cpu_median"])))
        table.append(row)
        if runs:
            fails = {k: {r["set"] for r in runs if (r["integrator"], r["newton_solver"]) == k
                         and r["status"] != "equilibrium"} for k in kinds}
            res = [r["residual"] for r in runs if r["status"] != "equilibrium"
                   and r["residual"]]
            both = fails[kinds[0]] & fails[kinds[1]]
            detail.append([label or "—", ", ".join(sorted({r["status"] for r in runs
                                                           if r["status"] != "equilibrium"}))
                           or "—", span(res, lambda v: num(v, 2)),
                           "%d / %d / %d" % (len(fails[kinds[0]]), len(fails[kinds[1]]),
                                             len(both))])
    text = ("stops.sh: N parameter sets drawn from the ICA box (seed S) run to equilibrium; "
            "each cell = runs that ended in `equilibrium` (median CPU of all its runs). Scene, "
            "N, rtol and seed from each run's manifest command, the binary from its "
            "`knitsim`.\n\n" + md_table(
                ["label", "scene", "N", "rtol", "seed", "knitsim", "cvode-bdf `ldl`",
                 "cvode-bdf `cg-ldl`", "`static`"], table))
    if detail:
        text += ("\nThe runs that did not settle (from the per-run CSV where kept): their "
                 "status, final residual range, and the sets unsettled with `ldl` / with "
                 "`cg-ldl` / with both.\n\n" + md_table(
                     ["label", "status", "residual", "unsettled ldl / cg-ldl / both"], detail))
    return "Stops inside the fit box (stops.sh)", text


def build(folder):
    sections = []
    for s in [drape_section(folder), knit_sweep_section(folder)] + \
            knit_timed_sections(folder) + [knit_drape_section(folder), stops_section(folder)]:
        if s:
            sections.append(s)
    sources = sorted(os.path.basename(p) for p in glob.glob(os.path.join(folder, "*.csv"))
                     + glob.glob(os.path.join(folder, "*manifest.json")))
    return "benchmark: tables", sources, sections


def main(argv=None):
    return summary_main("benchmark", build, argv)


if __name__ == "__main__":
    main()
