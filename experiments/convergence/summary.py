#!/usr/bin/python3
"""Tables of experiments/convergence from its CSV files only (orders.csv, orders_fit.csv,
tolerance.csv, tolerance_fit.csv, mesh.csv, ica.csv, manifest.json) -> summary.md; the README
points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/convergence/results)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (loglog_slope, md_table, median, num, provenance, read_json,  # noqa: E402
                    read_rows, span, summary_main)


def pivot(rows, key, col, value, fmt, keys_sorted):
    """A table with one row per `key` value and one column per `col` value."""
    cols = list(dict.fromkeys(r[col] for r in rows))
    cells = {(float(r[key]), r[col]): r[value] for r in rows}
    out = []
    for k in keys_sorted:
        out.append([k] + [fmt(cells[(k, c)]) if (k, c) in cells else "—" for c in cols])
    return cols, out


def build(out):
    orders, ofit = read_rows(out, "orders.csv"), read_rows(out, "orders_fit.csv")
    tol, tfit = read_rows(out, "tolerance.csv"), read_rows(out, "tolerance_fit.csv")
    mesh, ica = read_rows(out, "mesh.csv"), read_rows(out, "ica.csv")
    manifest = read_json(out, "manifest.json")
    sections = []

    text = ""
    if ofit:
        text += ("Observed order: least-squares slope of log error against log dt over the "
                 "series, and the slope of the last halving alone.\n\n" + md_table(
                     ["integrator", "expected order", "fitted slope", "last halving",
                      "dt range (s)"],
                     [[r["integrator"], r["expected"], "%.3f" % float(r["fitted"]),
                       "%.3f" % float(r["last_halving"]),
                       "%s – %s" % (num(r["dt_min"]), num(r["dt_max"]))] for r in ofit]))
    if orders:
        dts = sorted({float(r["dt"]) for r in orders}, reverse=True)
        cols, rows = pivot(orders, "dt", "integrator", "error_m", lambda v: num(v), dts)
        t_end = manifest.get("plan", {}).get("t_end")
        text += ("\nError at t_end%s (max over particles of |x - x_ref|, m) for each dt:\n\n"
                 % (" = %s s" % num(t_end) if t_end else "")
                 + md_table(["dt (s)"] + cols, [[num(r[0])] + r[1:] for r in rows]))
    sections.append(("(a) Orders of the fixed-step methods (orders_fit.csv, orders.csv)", text))

    text = ""
    if tfit:
        text += ("Slope of log error against log rtol (atol = 1e-3 rtol) and the error at rtol "
                 "1e-6.\n\n" + md_table(
                     ["integrator", "slope", "error at rtol 1e-6 (m)"],
                     [[r["integrator"], "%.2f" % float(r["slope"]),
                       num(r["error_at_rtol_1e_6"], 2)] for r in tfit]))
    if tol:
        rtols = sorted({float(r["rtol"]) for r in tol}, reverse=True)
        cols, rows = pivot(tol, "rtol", "integrator", "error_m", lambda v: num(v, 2), rtols)
        text += ("\nError at t_end (m) for each rtol:\n\n"
                 + md_table(["rtol"] + cols, [[num(r[0], exp=True)] + r[1:] for r in rows]))
        cols, rows = pivot(tol, "rtol", "integrator", "steps", str, rtols)
        text += ("\nSteps for each rtol:\n\n"
                 + md_table(["rtol"] + cols, [[num(r[0], exp=True)] + r[1:] for r in rows]))
    sections.append(("(b) Error against tolerance (tolerance_fit.csv, tolerance.csv)", text))

    if mesh:
        rows = []
        for r in mesh:
            rows.append([r["n"], "%.3f" % (100 * float(r["natural_length_m"])), r["particles"],
                         "%.4g" % float(r["damping"]), r["status"], r["steps"],
                         num(r["t_final"]), num(r["cpu_seconds"]),
                         "%.4f" % (100 * float(r["centre_sag_m"])),
                         num(100 * float(r["sag_diff_to_finest_m"]), 3),
                         num(r["coeff_diff_to_finest_pct"], 3)])
        text = ("four_corner at L0 = W / n (W = 50 cm), damping scaled with the particle mass; "
                "differences to the finest mesh: centre sag and Eq. 5 edge coefficients (top "
                "edge).\n\n" + md_table(
                    ["n", "L0 (cm)", "particles", "c (N·s/m)", "status", "steps", "t_final (s)",
                     "CPU (s)", "centre sag (cm)", "sag - finest (cm)",
                     "Eq. 5 vs finest (%)"], rows))
        sag = {int(r["n"]): 100 * float(r["centre_sag_m"]) for r in mesh}
        halvings = [[("%d → %d" % (n, 2 * n)), "%.4f" % (sag[2 * n] - sag[n])]
                    for n in sorted(sag) if 2 * n in sag]
        if halvings:
            text += ("\nCentre sag added by each halving of L0 present in the data:\n\n"
                     + md_table(["n → 2n", "sag increase (cm)"], halvings))
        slope = loglog_slope([float(r["particles"]) for r in mesh],
                             [float(r["cpu_seconds"]) for r in mesh])
        text += ("\nCPU per drape ∝ particles^%.2f (least-squares slope over the %d meshes).\n"
                 % (slope, len(mesh)))
        sections.append(("(c) Mesh refinement (mesh.csv)", text))

    if ica:
        rows = []
        for problem in dict.fromkeys(r["problem"] for r in ica):
            pr = [r for r in ica if r["problem"] == problem]
            seeds = list(dict.fromkeys(r["seed"] for r in pr))
            last = max(int(r["decade"]) for r in pr)
            mid = last // 2

            def at(decade):
                return [r for r in pr if int(r["decade"]) == decade]
            first_rows, mid_rows, end_rows = at(0), at(mid), at(last)
            rows.append([problem, pr[0]["dim"], len(seeds), last,
                         span([r["evaluations"] for r in end_rows], num),
                         span([r["best"] for r in first_rows], lambda v: num(v, 3)),
                         "%s (%s evaluations)" % (span([r["best"] for r in mid_rows],
                                                       lambda v: num(v, 3)),
                                                  span([r["evaluations"] for r in mid_rows], num)),
                         span([r["best"] for r in end_rows], lambda v: num(v, 3)),
                         num(median([r["best"] for r in end_rows]), 3)])
        text = ("Best cost over the seeds (range) at decade 0, at the middle decade and at the "
                "end; `fit_four_corner` is `knitsim fit` against a target from the default "
                "drape's own edges (Eq. 5, %; the right answer is 0).\n\n" + md_table(
                    ["problem", "dim", "seeds", "decades", "evaluations", "best at decade 0",
                     "best at the middle decade", "final best", "final median"], rows))
        fits = [p for p in dict.fromkeys(r["problem"] for r in ica) if p.startswith("fit")]
        for problem in fits:
            pr = [r for r in ica if r["problem"] == problem]
            srows = []
            for seed in dict.fromkeys(r["seed"] for r in pr):
                sr = sorted((r for r in pr if r["seed"] == seed), key=lambda r: int(r["decade"]))
                final = float(sr[-1]["best"])
                found = next(r for r in sr if float(r["best"]) == final)
                srows.append([seed, num(sr[0]["best"], 4), num(final, 4), found["evaluations"],
                              sr[-1]["evaluations"]])
            text += ("\n`%s` per seed:\n\n" % problem + md_table(
                ["seed", "best at decade 0", "final best", "evaluations when the final best was "
                 "found (end of its decade)", "evaluations in all"], srows))
        sections.append(("(d) ICA best cost against evaluations (ica.csv)", text))
    sections.append(("Provenance", provenance(manifest)))
    return ("convergence: tables",
            ["orders.csv", "orders_fit.csv", "tolerance.csv", "tolerance_fit.csv", "mesh.csv",
             "ica.csv", "manifest.json"], sections)


def main(argv=None):
    return summary_main("convergence", build, argv)


if __name__ == "__main__":
    main()
