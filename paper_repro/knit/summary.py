#!/usr/bin/python3
"""Tables of paper_repro/knit (paper 2's Figs. 8-10) from its CSV files only (runs.csv,
features.csv, stitch_features.csv, manifest.json) -> summary.md; the README points at them.
Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: paper_repro/knit/results)
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "experiments"))
import expkit  # noqa: E402
from expkit import md_table, provenance, read_json, read_rows  # noqa: E402

VARIANTS = ("paper", "stabilised", "contact")
R = "/ r"


def runs_table(rows):
    return md_table(["chart", "variant", "integrator", "status", "steps", "wall (s)",
                     "max displacement " + R, "min clearance over the run " + R,
                     "crossings changed"],
                    [[r["chart"], r["variant"], r["integrator"], r["status"], r["steps"],
                      r["wall_s"], r["max_displacement_over_r"], r["min_clearance_over_r"],
                      r["crossings_changed"]] for r in rows])


def single_tuck_table(rows):
    return md_table(["variant", "held loop height, start -> end " + R,
                     "its centre rises " + R, "tuck loop's centre rises " + R,
                     "lateral shift toward the tuck, k = 1, 2, 3, 4 " + R],
                    [[r["variant"], "%s -> %s" % (r["held_loop_height_start_r"],
                                                  r["held_loop_height_end_r"]),
                      r["held_loop_centre_rise_r"], r["tuck_loop_centre_rise_r"],
                      ", ".join(r["lateral_dx_toward_tuck_r_d%d" % k] for k in range(1, 5))]
                     for r in rows])


def span_of(rows, key):
    """'lo .. hi' of the non-empty values of `key`, or '' when there are none."""
    v = sorted(float(r[key]) for r in rows if r[key] != "")
    if not v:
        return ""
    return "%.2f" % v[0] if v[0] == v[-1] else "%.2f .. %.2f" % (v[0], v[-1])


def stitch_overview(rows):
    out = []
    for chart in sorted({r["chart"] for r in rows}, key=lambda c: [r["chart"] for r in rows]
                        .index(c)):
        for variant in VARIANTS:
            sel = [r for r in rows if r["chart"] == chart and r["variant"] == variant]
            if not sel:
                continue
            out.append([chart, variant, len(sel),
                        "%s -> %s" % (span_of(sel, "held_loop_height_rest_r"),
                                      span_of(sel, "held_loop_height_end_r")),
                        ("%s -> %s" % (span_of(sel, "tuck_loop_height_rest_r"),
                                       span_of(sel, "tuck_loop_height_end_r"))
                         if span_of(sel, "tuck_loop_height_end_r") else ""),
                        ("%s -> %s" % (span_of(sel, "float_depth_rest_r"),
                                       span_of(sel, "float_depth_end_r"))
                         if span_of(sel, "float_depth_end_r") else "")])
    return md_table(["chart", "variant", "stitches", "held loop height, rest -> end " + R,
                     "tuck loop height, rest -> end " + R,
                     "float depth behind the face, rest -> end " + R], out)


def rest_end(r, key):
    """'rest -> end' of key_rest_r, key_end_r, or '' when the cell has no such measure."""
    end = r[key + "_end_r"]
    return "%s -> %s" % (r[key + "_rest_r"], end) if end else ""


def stitch_table(rows):
    return md_table(["chart", "variant", "stitch", "wale", "course", "held loop height",
                     "held loop length", "tuck loop height", "tuck loop length", "float depth",
                     "float length"],
                    [[r["chart"], r["variant"], r["stitch"], r["wale"], r["course"]] +
                     [rest_end(r, key) for key in ("held_loop_height", "held_loop_length",
                                                   "tuck_loop_height", "tuck_loop_length",
                                                   "float_depth", "float_length")]
                     for r in rows])


def build(folder):
    runs = read_rows(folder, "runs.csv")
    features = read_rows(folder, "features.csv")
    stitches = read_rows(folder, "stitch_features.csv")
    sections = [
        ("Every run (runs.csv)", runs_table(runs) if runs else ""),
        ("single_tuck: the held loop and the neighbouring wales (features.csv)",
         single_tuck_table(features) if features else ""),
        ("Tuck and miss stitches, per chart (stitch_features.csv)",
         stitch_overview(stitches) if stitches else ""),
        ("Every tuck and miss stitch (stitch_features.csv), rest -> end, / r",
         stitch_table(stitches) if stitches else ""),
        ("Provenance", provenance(read_json(folder, "manifest.json"))),
    ]
    return ("Paper 2's Figs. 8-10: measured features",
            ["runs.csv", "features.csv", "stitch_features.csv", "manifest.json"], sections)


if __name__ == "__main__":
    expkit.summary_main("knit_figures", build, script="paper_repro/knit/summary.py",
                        folder=os.path.join(HERE, "results"))
