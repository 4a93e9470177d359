#!/usr/bin/python3
"""Tables of experiments/tensile from its CSV files only (runs.csv, curves.csv, manifest.json)
-> summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/tensile/results)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import md_table, num, provenance, read_json, read_rows, summary_main  # noqa: E402


def build(out):
    runs, curves = read_rows(out, "runs.csv"), read_rows(out, "curves.csv")
    manifest = read_json(out, "manifest.json")
    sections = []
    rows = []
    for r in runs:
        run = [c for c in curves if c["chart"] == r["chart"] and c["direction"] == r["direction"]]
        strains = [float(c["strain"]) for c in run]
        top = strains.index(max(strains)) if strains else 0
        f = [float(c["force_per_width_N_per_m"]) for c in run]
        lat = [float(c["lateral_strain"]) for c in run]
        secant = (f[top] - f[0]) / strains[top] if strains and strains[top] > 0 else None
        rows.append([r["chart"], r["direction"], "%s x %s" % (r["wales"], r["courses"]),
                     num(r["initial_stiffness_N_per_m"], 4), num(secant, 4),
                     num(r["initial_poisson_ratio"], 3),
                     num(-(lat[top] - lat[0]) / strains[top], 3) if strains else "—",
                     num(f[-1] - f[0], 3) if run else "—", r["status"],
                     num(r["newton_steps_per_step"], 3), num(r["cpu_seconds"], 3)])
    sections.append((
        "Stiffness and Poisson's ratio (runs.csv, curves.csv)",
        "Initial: from step 0 (settled between the clamps) to step 1; secant: from step 0 to the "
        "largest strain. Stiffness is force per rest width per unit strain (N/m). Return: the "
        "force per width back at strain 0 after unloading minus that at step 0 (N/m; the "
        "contact's renewals are the network's only hysteresis). Newton: the equilibrium "
        "solver's flow steps per step; CPU: the steps' solves (s).\n\n" + md_table(
            ["chart", "pulled along", "specimen (wales x courses)", "initial stiffness",
             "secant stiffness", "initial Poisson", "secant Poisson", "return", "status",
             "Newton per step", "CPU (s)"], rows)))
    sections.append(("Provenance", provenance(manifest)))
    return ("Tensile study: the network's force-extension curves", ["runs.csv", "curves.csv",
                                                                     "manifest.json"], sections)


def main(argv=None):
    return summary_main("tensile", build, argv)


if __name__ == "__main__":
    main()
