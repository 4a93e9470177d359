#!/usr/bin/python3
"""Tables of experiments/stability from its CSV files only (limits.csv, map.csv, bdf.csv,
undamped.csv, manifest.json) -> summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/stability/results)
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, num, provenance, read_json, read_rows, sci,  # noqa: E402
                    span, summary_main)

PARAMS = (("stiffness", "k %s"), ("damping", "c %s"), ("areal_density", "%s g/m²"),
          ("natural_length", "L0 %s cm"))


def label(row, base):
    """A case by what differs from the base fabric: 'k 500', 'c 0, 27.6 g/m²', 'base'."""
    parts = []
    for key, fmt in PARAMS:
        v = float(row[key])
        if base and v != float(base[key]):
            parts.append(fmt % num(100 * v if key == "natural_length" else v, 4))
    return ", ".join(parts) or "base"


def limit(x):
    return "0" if x not in ("", None) and float(x) == 0 else sci(x, 4)


def build(out):
    limits = read_rows(out, "limits.csv")
    cells = read_rows(out, "map.csv")
    bdf = read_rows(out, "bdf.csv")
    undamped = read_rows(out, "undamped.csv")
    manifest = read_json(out, "manifest.json")
    base = manifest.get("base") or next((r for r in limits if r["group"] == "base"), None)
    sections = []

    cases = list(dict.fromkeys(r["case"] for r in limits))
    by = {(r["case"], r["method"]): r for r in limits}
    rows = []
    for c in cases:
        first = next(r for r in limits if r["case"] == c)
        row = [label(first, base)]
        for m in ("euler", "verlet"):
            r = by.get((c, m))
            if r is None:
                row.append("—")
                continue
            measured = "unstable at any dt" if float(r["measured"]) == 0 else sci(r["measured"], 4)
            row.append(" / ".join([limit(r["predicted"]), limit(r["estimated"]), limit(r["exact"]),
                                   measured]))
        r = by.get((c, "arkode-erk"))
        row.append("—" if r is None else "%s / %s" % (limit(r["exact"]), sci(r["measured"], 4)))
        rows.append(row)
    base_text = ""
    if base:
        base_text = ("Base fabric: k %s N/m, c %s N·s/m, %s g/m², L0 %s cm; each case changes "
                     "what its label names. " % (num(base["stiffness"], 4), num(base["damping"], 4),
                                            num(base["areal_density"], 4),
                                            num(100 * float(base["natural_length"]), 4)))
    sections.append((
        "Stability limits, s (limits.csv)",
        base_text + "predicted = `predict_stable_dt` (Gershgorin), estimated = "
        "`estimate_stable_dt` (Lanczos-capped), exact = the linear analysis of "
        "`linear_limits.py`, measured = bisection (euler, verlet) or the mean accepted step "
        "(arkode-erk).\n\n" + md_table(
            ["case", "euler predicted / estimated / exact / measured",
             "verlet predicted / estimated / exact / measured",
             "arkode-erk exact / measured mean step"], rows)))

    rows = []
    for c in cases:
        first = next(r for r in limits if r["case"] == c)
        row = [label(first, base)]
        for m in ("euler", "verlet", "arkode-erk"):
            r = by.get((c, m))
            if r is None:
                row.append("—")
                continue
            ratios = [r["measured_over_predicted"], r["measured_over_estimated"],
                      r["measured_over_exact"]]
            row.append(" / ".join("—" if not math.isfinite(float(x)) else "%.4f" % float(x)
                                  for x in ratios))
        rows.append(row)
    text = ("measured / predicted, measured / estimated, measured / exact (— where a limit is 0 "
            "or not defined).\n\n" + md_table(
                ["case", "euler", "verlet", "arkode-erk"], rows))
    ext = []
    for m in ("euler", "verlet"):
        for key in ("measured_over_exact", "measured_over_estimated", "measured_over_predicted"):
            vs = [(float(r[key]), r) for r in limits
                  if r["method"] == m and math.isfinite(float(r[key]))]
            if vs:
                lo, hi = min(vs, key=lambda v: v[0]), max(vs, key=lambda v: v[0])
                ext.append([m, key.replace("measured_over_", "measured / "),
                            "%.4f (%s)" % (lo[0], label(lo[1], base)),
                            "%.4f (%s)" % (hi[0], label(hi[1], base))])
    if ext:
        text += "\nExtremes over the cases:\n\n" + md_table(["method", "ratio", "smallest",
                                                              "largest"], ext)
    sections.append(("Measured limit against each prediction (limits.csv)", text))

    rows = []
    for m in dict.fromkeys(c["method"] for c in cells):
        for k in sorted({float(c["stiffness"]) for c in cells if c["method"] == m}):
            mc = [c for c in cells if c["method"] == m and float(c["stiffness"]) == k]
            stable = [c for c in mc if c["stable"] == "1"]
            unstable = [c for c in mc if c["stable"] != "1"]
            lim = [r for r in limits if r["method"] == m and r["group"] in ("base", "stiffness")
                   and float(r["stiffness"]) == k]
            rows.append([m, num(k), len(mc), len(stable),
                         sci(max(float(c["dt"]) for c in stable), 3) if stable else "—",
                         sci(min(float(c["dt"]) for c in unstable), 3) if unstable else "—",
                         sci(lim[0]["measured"], 4) if lim else "not measured",
                         num(max(float(c["error_m"]) for c in stable), 2) if stable else "—",
                         ", ".join(sorted(set(c["status"] for c in unstable))) or "—"])
    t_end = span([c["t_end"] for c in cells])
    sections.append((
        "Stability map (map.csv)",
        "euler and verlet at a grid of dt × stiffness (c and the rest at the base fabric), run to "
        "t = %s s; error = max position error against cvode-bdf at rtol 1e-10.\n\n" % t_end
        + md_table(["method", "k (N/m)", "cells", "stable", "largest stable dt (s)",
                    "smallest unstable dt (s)", "measured limit (s)", "largest error of a stable "
                    "cell (m)", "status of the unstable runs"], rows)
        + ("\nRuns of the study that blew up without writing a summary "
           "(manifest.json `blown_up_without_summary`): %s.\n"
           % manifest["blown_up_without_summary"] if "blown_up_without_summary" in manifest
           else "")))

    rows = []
    for r in bdf:
        rows.append([label(r, base), "default" if r["max_order_option"] == "0" else
                     "--max-order %s" % r["max_order_option"], r["status"], num(r["t_final"]),
                     r["steps"], r["err_test_fails"], r["nonlin_fails"], r["max_order_used"],
                     num(r["residual"], 2), num(r["cpu_seconds"])])
    sections.append((
        "cvode-bdf at the extremes (bdf.csv)",
        "To equilibrium (step cap in the driver), at the default maximum order and with "
        "`--max-order 2`.\n\n" + md_table(
            ["case", "order", "status", "t_final (s)", "steps", "error-test failures",
             "Newton failures", "max order used", "residual", "CPU (s)"], rows)))

    rows = []
    for r in undamped:
        rows.append([r["integrator"], "`%s`" % r["options"], r["status"], num(r["t_final"]),
                     r["steps"], num(r["dt"]) if float(r["dt"]) > 0 else "adaptive",
                     num(r["residual"], 2), r["err_test_fails"], num(r["cpu_seconds"])])
    sections.append((
        "No damping, c = 0 (undamped.csv)",
        md_table(["integrator", "options", "status", "t_final (s)", "steps", "dt (s)", "residual",
                  "error-test failures", "CPU (s)"], rows)))
    sections.append(("Where each method ends: spurious equilibria at the extremes (spurious.csv)",
                     spurious_table(read_rows(out, "spurious.csv"))))
    sections.append(("Provenance", provenance(manifest)))
    return ("stability: tables",
            ["limits.csv", "map.csv", "bdf.csv", "undamped.csv", "spurious.csv",
             "manifest.json"], sections)


def spurious_table(rows):
    """Per scene the runs of spurious.csv; '' without the file."""
    if not rows:
        return ""
    text = ("Whole sheets. Reference: the state the damped dynamics reach from rest, cvode-bdf at "
            "rtol 1e-8, atol 1e-11 (first row of each scene). Outcome: *same equilibrium* "
            "(status equilibrium, within 1e-6 m of the reference), *another minimum* (status "
            "equilibrium, certified, farther), *spurious* (status spurious_equilibrium: energy "
            "above the total energy the run had once the pins stopped), *saddle* (certificate "
            "not_minimum), *no equilibrium* (another status). Energy: the end state's potential "
            "energy; energy reference: the run's own `energy_reference` (its total energy once the "
            "pins stopped; 0 where the stop was never passed). *Above the dynamics' energy "
            "reference*: the end energy exceeds the reference run's `energy_reference`, so the "
            "damped dynamics cannot reach the state; **yes** in bold where knitsim still called it "
            "an equilibrium (the run's own reference was higher).\n\n")
    counts = {}
    for r in rows:
        counts.setdefault(r["scene"], {}).setdefault(r["outcome"].split(" (")[0], 0)
        counts[r["scene"]][r["outcome"].split(" (")[0]] += 1
    for scene in dict.fromkeys(r["scene"] for r in rows):
        table = []
        # The total energy the dynamics (the reference run) had once the pins stopped: a state
        # above it cannot be reached from rest, whatever the run's own energy_reference says.
        e_dyn = [float(r["energy_reference"]) for r in rows
                 if r["scene"] == scene and r["setting"] == "reference"][0]
        for r in rows:
            if r["scene"] != scene:
                continue
            above = r["status"] in ("equilibrium", "spurious_equilibrium") and \
                float(r["energy"]) > e_dyn
            table.append([r["integrator"], r["setting"], r["status"], r["certificate"] or "—",
                          r["outcome"], num(r["distance_m"], 2), num(r["energy"], 4),
                          num(r["energy_reference"], 4),
                          ("**yes**" if r["status"] == "equilibrium" else "yes") if above else "no",
                          r["steps"], num(r["cpu_seconds"])])
        text += ("**%s** (outcomes: %s)\n\n" % (scene, ", ".join(
            "%s %d" % kv for kv in sorted(counts[scene].items())))
                 + md_table(["integrator", "setting", "status", "certificate", "outcome",
                             "distance (m)", "energy (J)", "energy reference (J)",
                             "above the dynamics' energy reference", "steps", "CPU (s)"], table)
                 + "\n")
    return text


def main(argv=None):
    return summary_main("stability", build, argv)


if __name__ == "__main__":
    main()
