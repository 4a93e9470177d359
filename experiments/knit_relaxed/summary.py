#!/usr/bin/python3
"""Tables of experiments/knit_relaxed from its CSV files only (runs.csv, manifest.json) ->
summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/knit_relaxed/results)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import md_table, num, provenance, read_json, read_rows, summary_main  # noqa: E402

# The dimensional constants of plain jersey (wool; Munden; Knapton et al. 1968): K_c, K_w, K_s, R.
WET = {"K_c": 5.3, "K_w": 4.1, "K_s": 21.6, "R": 1.3}  # wet (fully) relaxed: the scored set
DRY = {"K_c": 5.0, "K_w": 3.8, "K_s": 19.0, "R": 1.3}  # dry relaxed: set beside it
KEYS = ("K_c", "K_w", "K_s", "R")


def pct(model, ref):
    return 100.0 * (model / ref - 1.0)


def build(out):
    runs = read_rows(out, "runs.csv")
    manifest = read_json(out, "manifest.json")
    f = lambda r, k: float(r[k]) if r.get(k) not in (None, "", "None") else float("nan")  # noqa
    sections = []
    lit = [r for r in runs if r["part"] == "literature"]
    rows = []
    for r in lit:
        row = [num(r["tightness_factor"], 3), num(1e3 * f(r, "stitch_length_m"), 4),
               num(r["courses_per_cm"], 4), num(r["wales_per_cm"], 4)]
        for k in KEYS:
            row.append("%s (%+.1f %% wet, %+.1f %% dry)" % (num(r[k], 3), pct(f(r, k), WET[k]),
                                                           pct(f(r, k), DRY[k])))
        within = all(abs(pct(f(r, k), WET[k])) <= 10.0 for k in ("K_s", "R"))
        row += ["yes" if within else "no", num(r["clearance_min_over_d"], 3), r["status"]]
        rows.append(row)
    sections.append((
        "Relaxed plain jersey against the dimensional constants (runs.csv, part literature)",
        "The model (frictionless yarn, minimum energy) against the wet-relaxed set (wool; Munden; "
        "Knapton et al. 1968: K_c 5.3, K_w 4.1, K_s 21.6, R 1.3; the scored set) and the dry-"
        "relaxed set beside it (5.0, 3.8, 19, 1.3). Target: K_s and R within +-10 % of the wet "
        "set. l: the knitted stitch length (yarn per loop).\n\n" + md_table(
            ["tightness factor", "l (mm)", "courses/cm", "wales/cm", "K_c", "K_w", "K_s", "R",
             "K_s and R within 10 % (wet)", "least clearance (d)", "status"], rows)))
    loop = [r for r in runs if r["part"] == "loop_length"]
    if loop:
        rows = [[num(1e3 * f(r, "stitch_length_m"), 4), num(r["tightness_factor"], 3),
                 num(r["courses_per_cm"], 4), num(r["wales_per_cm"], 4), num(r["K_c"], 3),
                 num(r["K_w"], 3), num(r["K_s"], 3), num(r["R"], 3), r["status"]] for r in loop]
        spread = []
        for k in KEYS:
            vals = [f(r, k) for r in loop]
            mean = sum(vals) / len(vals)
            spread.append("%s %.1f %%" % (k, 100.0 * (max(vals) - min(vals)) / mean))
        sections.append((
            "Doyle and Munden: the K values against the loop length (runs.csv, part loop_length)",
            "l varied about the tightness-1.47 stitch length at the fixed default yarn. Spread "
            "(max - min over the mean) of each constant over the sweep: " + ", ".join(spread) +
            " (the literature: a few per cent; goal <= 10 %).\n\n" + md_table(
                ["l (mm)", "tightness factor", "courses/cm", "wales/cm", "K_c", "K_w", "K_s", "R",
                 "status"], rows)))
    conv = [r for r in runs if r["part"] == "convergence"]
    if conv:
        conv.sort(key=lambda r: int(r["edges_per_wale"]))
        rows = []
        for i, r in enumerate(conv):
            dc = dw = "—"
            if i > 0:
                p = conv[i - 1]
                dc = "%+.2f %%" % pct(f(r, "courses_per_cm"), f(p, "courses_per_cm"))
                dw = "%+.2f %%" % pct(f(r, "wales_per_cm"), f(p, "wales_per_cm"))
            rows.append([r["edges_per_wale"], num(r["courses_per_cm"], 5), dc,
                         num(r["wales_per_cm"], 5), dw, num(r["steps"], 4),
                         num(r["cpu_seconds"], 3), r["status"]])
        sections.append((
            "Segment length (runs.csv, part convergence)",
            "The cell at the tightness-1.47 stitch length with knit.yarn_vertices edges per wale "
            "(vertices per loop); change against the row above (target: < 1 % when the edge "
            "length halves).\n\n" + md_table(
                ["vertices per loop", "courses/cm", "change", "wales/cm", "change", "steps",
                 "CPU (s)", "status"], rows)))
    pat = {r["label"]: r for r in runs if r["part"] == "pattern"}
    if "plain" in pat:
        p0 = pat["plain"]
        w0 = f(p0, "width_m") / 1.0  # plain: a 1 x 1 cell
        h0 = f(p0, "height_m") / 1.0
        hk0 = f(p0, "knit_loop_height_m")
        rows = []
        for label in ("plain", "tuck", "miss"):
            if label not in pat:
                continue
            r = pat[label]
            nw = len(r["repeat"].split("/")[0]) if r.get("repeat") else 1
            nc = len(r["repeat"].split("/")) if r.get("repeat") else 1
            w, h = f(r, "width_m") / nw, f(r, "height_m") / nc
            held = f(r, "held_loop_height_m")
            tm = r.get("tm_stitch") or ""
            rows.append([
                label, r.get("repeat") or "", num(r["courses_per_cm"], 4),
                num(r["wales_per_cm"], 4), "%+.1f %%" % pct(w, w0), "%+.1f %%" % pct(h, h0),
                num(1e3 * f(r, "knit_loop_height_m"), 3),
                "—" if held != held else "%s (%.2f x plain)" % (num(1e3 * held, 3), held / hk0),
                "—" if not tm else "%s: %s" % (tm, num(1e3 * f(r, "tm_width_m"), 3)),
                "—" if not tm else num(r["tm_straightness"], 3),
                "—" if not tm else "%+.2f" % f(r, "tm_z_behind_knit_over_d"), r["status"]])
        sections.append((
            "Tuck and miss patterns beside plain jersey (runs.csv, part pattern)",
            "2 x 2 repeats relaxed as periodic cells at l = 3.4 mm (every course's yarn per "
            "wale; tuck and float cells at the knit's ratio of their start length): the 1 x 1 "
            "tuck pattern KT / KK (a tuck on alternate needles in alternate courses) and the 1 x "
            "1 miss pattern KM / KK, beside plain jersey (K). Width and length: per wale and per "
            "course (cell width / wales, height / courses) against plain jersey's. Loop "
            "heights: the vertical extent of one wale's yarn, sinker to sinker, in course 0 "
            "(the knit loop on wale 1; the held loop on wale 2, under the tuck or the miss). "
            "Tuck / float: the yarn of course 1 on wale 2, its width (mm) and straightness "
            "(chord over yarn length; 1 is straight) and its mean z less that of the knit loop beside it (d; "
            "negative: behind, the knit's legs come forward in +z). The literature (issue 51 item 3): tuck "
            "fabric wider and shorter, miss fabric narrower, held loops elongated, floats "
            "straight behind the face.\n\n" + md_table(
                ["fabric", "repeat (top first)", "courses/cm", "wales/cm", "width per wale",
                 "length per course", "knit loop height (mm)", "held loop height (mm)",
                 "tuck / float width (mm)", "tuck / float straightness",
                 "tuck / float z - knit's (d)", "status"], rows)))
    curves = read_rows(out, "curves.csv")
    if curves:
        rows = []
        for direction in ("course", "wale"):
            c = [x for x in curves if x["direction"] == direction]
            if len(c) < 2:
                continue
            e = [float(x["strain"]) for x in c]
            fw = [float(x["force_per_width_N_per_m"]) for x in c]
            lat = [float(x["lateral_strain"]) for x in c]
            k1 = (fw[1] - fw[0]) / (e[1] - e[0])
            kn = (fw[-1] - fw[-2]) / (e[-1] - e[-2])
            rows.append([direction, num(k1, 3), num(kn, 3), num(e[-1], 3), num(fw[-1], 3),
                         num(-(lat[1] - lat[0]) / (e[1] - e[0]), 3), num(-lat[-1] / e[-1], 3),
                         c[-1]["status"]])
        sections.append((
            "Tensile: the relaxed cell pulled along the courses and the wales (curves.csv)",
            "The relaxed tightness-1.47 cell stretched in steps of 0.01 along the courses (W "
            "held, H free) or the wales (H held, W free). Force per rest width: the reaction "
            "dE/dW over H0, or dE/dH over W0 (N/m). Initial and final tangent stiffness: from "
            "the first and the last step (N/m per unit strain); Poisson: -lateral strain / "
            "strain, over the first step and at the end.\n\n" + md_table(
                ["pulled along", "initial stiffness (N/m)", "final tangent (N/m)", "strain",
                 "force per width (N/m)", "initial Poisson", "Poisson at the end", "status"],
                rows)))
    rows = [[r["part"], r["label"], num(r["steps"], 4), num(r["cpu_seconds"], 3),
             num(r["dof"], 4), "%.1e" % f(r, "course_length_change_max"),
             "%.1e" % f(r, "dE_dW_N"), "%.1e" % f(r, "dE_dH_N")] for r in runs]
    sections.append((
        "Cost and checks (runs.csv)",
        "Steps and CPU seconds of the whole run (every ramp stage, equilibrium solver); the "
        "yarn's largest relative length change against the knitted length; the cell's "
        "generalised forces dE/dW, dE/dH at the end (N per cell, 0 at a relaxed state).\n\n" +
        md_table(["part", "run", "steps", "CPU (s)", "dof", "length change", "dE/dW (N)",
                  "dE/dH (N)"], rows)))
    sections.append(("Provenance", provenance(manifest)))
    return ("knit_relaxed: relaxed plain jersey from the periodic yarn cell",
            ["runs.csv", "curves.csv", "manifest.json"], sections)


def main(argv=None):
    return summary_main("knit_relaxed", build, argv)


if __name__ == "__main__":
    main()
