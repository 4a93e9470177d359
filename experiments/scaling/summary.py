#!/usr/bin/python3
"""Tables of the scaling study from its CSV files only -> summary.md; the README points at
them. Standard library only (plot.py imports medians() and slope() from here).

    summary.py [DIR] [--output FILE]     (default DIR: experiments/scaling/data)

Reads every PREFIX`runs.csv` in DIR (run.sh writes runs.csv; the committed data/ keeps each
run under its own prefix: quick_, equilibrium_, target_, eighth_, block_, factorization_,
flops_) with its
PREFIX`manifest.json`, PREFIX`nested_runs.csv` of nested.py, and the knitsim summary.json
files n100_*_summary.json. Per runs file: every (solver, grid) as the median of its rounds
(the run with the median CPU time), the growth exponents of CPU time and steps against the
particle count over the settled runs (least squares on log-log, as plot.py's fit.csv), the
CPU per back end where the runs differ by --factorization, and the work of the factorisations
where the runs report factor_flops.
"""
import glob
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, num, provenance, read_json, read_rows,  # noqa: E402
                    summary_main)

TITLES = {
    "": "Runs (runs.csv)",
    "quick_": "Quick mode: every solver at n = 10, 20, 40 (quick_runs.csv)",
    "target_": "Target: a 101×101 equilibrium, n = 100 on the eighth and the quarter "
               "(target_runs.csv)",
    "eighth_": "Beyond 101×101 on the eighth (eighth_runs.csv)",
    "equilibrium_": "The equilibrium solver, whole sheet and as the default runs it "
                    "(model.symmetry = auto: the eighth), n = 10 to 200 (equilibrium_runs.csv)",
    "block_": "Factorisation back ends: 3×3 block LDLᵀ, simplicial, supernodal (block_runs.csv)",
    "factorization_": "Factorisation back ends: supernodal (automatic) against simplicial "
                      "(factorization_runs.csv)",
    "flops_": "Flops of the factorisations (flops_runs.csv)",
}
ORDER = ["", "quick_", "equilibrium_", "target_", "eighth_", "block_", "factorization_", "flops_"]


def slope(xs, ys):
    """Least-squares slope of log(y) on log(x); None with fewer than two points."""
    if len(xs) < 2:
        return None
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx


def medians(rows):
    """One row per (solver, particles): the run with the median CPU time of its rounds (the
    lower median for an even count), plus the rounds' count, minimum and maximum CPU."""
    groups = {}
    for r in rows:
        groups.setdefault((r["solver"], r["particles"]), []).append(r)
    out = []
    for rs in groups.values():
        timed = sorted((r for r in rs if r["cpu_seconds"]), key=lambda r: float(r["cpu_seconds"]))
        pick = dict(timed[(len(timed) - 1) // 2] if timed else rs[0])
        cpus = [float(r["cpu_seconds"]) for r in timed]
        flops = pick.get("factor_flops") or ""
        work = (float(flops) * int(pick["factorisations"]) / 1e9
                if flops and pick["factorisations"] else "")
        pick.update(factorisation_gflop=work)
        pick.update(rounds=len(rs), cpu_min=min(cpus) if cpus else "",
                    cpu_max=max(cpus) if cpus else "",
                    cpu_median=statistics.median(cpus) if cpus else "",
                    cpu_rounds=[float(r["cpu_seconds"]) for r in rs if r["cpu_seconds"]])
        out.append(pick)
    return out


def fits(rows):
    """Per solver: points, CPU and steps exponents over the settled runs, largest particles."""
    out = []
    for s in dict.fromkeys(r["solver"] for r in rows):
        eq = [r for r in rows if r["solver"] == s and r["cpu_seconds"]
              and r["status"] == "equilibrium"]
        px = [int(r["particles"]) for r in eq]
        out.append(dict(solver=s, points=len(eq),
                        cpu_exponent=slope(px, [float(r["cpu_seconds"]) for r in eq]),
                        steps_exponent=slope(px, [max(1, int(r["steps"])) for r in eq]),
                        largest_particles=max(px) if px else 0))
    return out


def status(r):
    s = r["status"]
    if s != "equilibrium" and r.get("residual"):
        s += " (residual %s)" % num(r["residual"], 2)
    return s


def runs_section(folder, prefix):
    rows = medians(read_rows(folder, prefix + "runs.csv"))
    rows.sort(key=lambda r: (int(r["particles"]), r["solver"]))
    has_factorization = any(r.get("factorization") for r in rows)
    rounds = max(r["rounds"] for r in rows)
    head = ["particles", "n", "solver"] + (["back end"] if has_factorization else []) + \
        ["dof integrated", "status", "residual", "t_final (s)", "steps", "set-ups",
         "factorisations", "CPU (s)" if rounds == 1 else "CPU median (range), s",
         "peak RSS (MiB)", "centre sag (cm)"]
    table = []
    for r in rows:
        cpu = num(r["cpu_median"])
        if r["rounds"] > 1:
            cpu += " (%s–%s, %d rounds)" % (num(r["cpu_min"]), num(r["cpu_max"]), r["rounds"])
        table.append([r["particles"], r["n"], r["solver"]]
                     + ([r.get("factorization") or "—"] if has_factorization else [])
                     + [r["integrated_dof"], r["status"], num(r["residual"], 2),
                        num(r["t_final"]), r["steps"],
                        r["lin_setups"], r["factorisations"], cpu,
                        "%.0f" % (float(r["max_rss_kb"]) / 1024) if r["max_rss_kb"] else "—",
                        "%.4f" % (100 * float(r["centre_sag_m"]))
                        if r["status"] == "equilibrium" else "—"])
    text = ("One row per solver and grid (rounds as the run with the median CPU time); the "
            "final static residual (equilibrium_tol 1e-8; an `equilibrium` above it stopped at "
            "the mesh's round-off floor); CPU = the solver's own `cpu_seconds`; peak RSS of the "
            "whole process; the centre sag of the runs that settled.\n\n"
            + md_table(head, table))

    fit = [f for f in fits(rows) if f["points"] >= 3]
    if fit:
        text += ("\nGrowth over the settled runs (least squares on log-log): CPU ∝ "
                 "particles^p, steps ∝ particles^q.\n\n" + md_table(
                     ["solver", "points", "p (CPU)", "q (steps)", "largest particles"],
                     [[f["solver"], f["points"], "%.2f" % f["cpu_exponent"],
                       "%.2f" % f["steps_exponent"], f["largest_particles"]] for f in fit]))

    grids = sorted({int(r["particles"]) for r in rows})
    # Back ends side by side only where every run of a grid integrates the same model.
    one_model = all(len({r["integrated_dof"] for r in rows if int(r["particles"]) == p}) == 1
                    for p in grids)
    if has_factorization and one_model and len({r["factorization"] for r in rows}) > 1:
        backs = sorted({r["factorization"] for r in rows})
        piv = []
        for p in grids:
            at = {r["factorization"]: r for r in rows if int(r["particles"]) == p}
            first = next(iter(at.values()))
            piv.append([p, first["n"], first["integrated_dof"],
                        "%s / %s" % (first["steps"], first["factorisations"])]
                       + [", ".join(num(c) for c in at[b]["cpu_rounds"]) if b in at else "—"
                          for b in backs])
        text += ("\nCPU seconds per back end (`--factorization`), each round:\n\n"
                 + md_table(["particles", "n", "dof", "steps / factorisations"]
                            + ["%s CPU (s)" % b for b in backs], piv))

    if any(r.get("factor_flops") for r in rows):
        flops = []
        for r in rows:
            if not r.get("factor_flops"):
                continue
            work = float(r["factorisation_gflop"])
            flops.append([r["particles"], r["integrated_dof"], r["solver"],
                          num(r["factor_nonzeros"]), num(r["factor_flops"]), r["factorisations"],
                          "%s GFlop" % num(work, 3), num(r["cpu_median"]),
                          "%.2g GFlop/s" % (work / float(r["cpu_median"]))])
        text += ("\nOne symmetric factorisation (S of docs/numerics.md, or C / h + K for the "
                 "equilibrium solver): `factor_nonzeros` = nnz(L), `factor_flops` = "
                 "CHOLMOD's count; their work = factorisations × flops.\n\n"
                 + md_table(["particles", "unknowns", "solver", "nnz(L)",
                             "flops per factorisation", "factorisations", "their work",
                             "CPU of the run (s)", "work / CPU"], flops))
        for s in dict.fromkeys(r["solver"] for r in rows):
            pts = [r for r in rows if r["solver"] == s and r.get("factor_flops")]
            e = slope([int(r["particles"]) for r in pts], [float(r["factor_flops"]) for r in pts])
            if e is not None:
                text += ("\nFlops per factorisation ∝ particles^%.2f over the %d %s runs.\n"
                         % (e, len(pts), s))
    text += "\n" + provenance(read_json(folder, prefix + "manifest.json"),
                              prefix + "manifest.json")
    return TITLES.get(prefix, "%sruns.csv" % prefix), text


def nested_section(folder, name):
    rows = read_rows(folder, name)
    prefix = name[: -len("nested_runs.csv")]
    table = []
    for r in rows:
        coarse = r.get("coarse_cpu_seconds")
        table.append([r["n"], r["particles"],
                      "from flat" if r["route"] == "flat" else "from the n = %d equilibrium"
                      % (int(r["n"]) // 2) if r["route"] == "nested" else r["route"],
                      status(r), r["steps"], r["factorisations"],
                      num(r["cpu_seconds"]) + (" (coarse %s)" % num(coarse) if coarse else ""),
                      num(r["start_residual"], 2),
                      num(r["max_position_difference_m"], 2) if r["route"] != "flat" else "—"])
    text = ("`static` on the full sheet from the flat state and from the interpolated "
            "equilibrium of the n/2 grid (nested.py); CPU = the solver's `cpu_seconds`, the "
            "nested route's including the coarse run's; start residual = the static residual "
            "after the first step; distance = max over particles to the flat route's "
            "equilibrium.\n\n" + md_table(
                ["n", "particles", "route", "status", "steps", "factorisations", "CPU (s)",
                 "start residual", "max distance to the flat route's equilibrium (m)"], table))
    text += "\n" + provenance(read_json(folder, prefix + "nested_manifest.json"),
                              prefix + "nested_manifest.json")
    return "Coarse-to-fine start, full sheet (%s)" % name, text


def single_runs_section(folder):
    paths = sorted(glob.glob(os.path.join(folder, "n*_summary.json")))
    if not paths:
        return None
    table = []
    for path in paths:
        s = read_json(folder, os.path.basename(path))
        g = s.get("grid", {})
        table.append([os.path.basename(path), g.get("particles", "—"), s.get("integrator", "—"),
                      g.get("integrated_dof", "—"), s.get("status", "—"), num(s.get("t_final")),
                      s.get("steps", "—"), s.get("lin_setups", "—"), num(s.get("cpu_seconds")),
                      num(s.get("residual"), 2), "%.4f" % (100 * s["centre_sag_m"])
                      if "centre_sag_m" in s else "—"])
    return ("Single full-grid runs at n = 100 (knitsim summary.json)",
            "`knitsim drape --scene four_corner --set model.natural_length=0.005 --set "
            "model.damping=0.12494793835901708 [--integrator static]`, one run each.\n\n"
            + md_table(["file", "particles", "integrator", "dof", "status", "t_final (s)",
                        "steps", "set-ups", "CPU (s)", "residual", "centre sag (cm)"], table))


def build(folder):
    names = sorted(os.path.basename(p) for p in glob.glob(os.path.join(folder, "*runs.csv")))
    nested = [nested_section(folder, n) for n in names if n.endswith("nested_runs.csv")]
    prefixes = [n[: -len("runs.csv")] for n in names if not n.endswith("nested_runs.csv")]
    prefixes.sort(key=lambda p: (ORDER.index(p) if p in ORDER else len(ORDER), p))
    sections = [runs_section(folder, p) for p in prefixes]
    # nested.py runs with run.sh --quick: its section follows the quick (or only) runs section
    at = next((i + 1 for i, p in enumerate(prefixes) if p in ("", "quick_")), len(sections))
    sections[at:at] = nested
    single = single_runs_section(folder)
    if single:
        sections.append(single)
    sources = names + sorted(os.path.basename(p) for p in
                             glob.glob(os.path.join(folder, "*manifest.json")) +
                             glob.glob(os.path.join(folder, "n*_summary.json")))
    return "scaling: tables", sources, sections


def main(argv=None):
    return summary_main("scaling", build, argv)


if __name__ == "__main__":
    main()
