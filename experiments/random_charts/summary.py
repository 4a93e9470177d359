#!/usr/bin/python3
"""Tables of experiments/random_charts from its CSV file only (random_charts.csv, manifest.json)
-> summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/random_charts/results)
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import (md_table, median, num, percentile, provenance, read_json,  # noqa: E402
                    read_rows, span, summary_main)

STUDY = "random_charts"
CSV = "random_charts.csv"
# The same charts without yarn contact (run.sh -- --set knit.contact=0), its CSV and manifest
# renamed: the second part of summary.md when present.
BARE_CSV, BARE_MANIFEST = "random_charts_no_contact.csv", "manifest_no_contact.json"
WORST = 5
WARN = 0.9  # r: knitsim's warning threshold and the clearance target


def value(r, key):
    """A finite float of row r, or None."""
    v = r.get(key, "")
    if v in ("", None):
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def values(rows, key):
    return [v for v in (value(r, key) for r in rows) if v is not None]


def crossings(r):
    return "%s of %s" % (r["crossings_changed"] or "—", r["crossings_designed"] or "—")


def runs_section(rows, manifest):
    statuses = {}
    for r in rows:
        key = (r["status"], r["exit_code"])
        statuses[key] = statuses.get(key, 0) + 1
    body = md_table(["status", "exit code", "charts"],
                    [[s, e, n] for (s, e), n in sorted(statuses.items(),
                                                       key=lambda kv: (-kv[1], kv[0]))])
    cpu = values(rows, "cpu_seconds")
    wall = manifest.get("wall_seconds")
    body += "\n" + md_table(
        ["charts", "seed", "P(tuck) = P(miss) per eligible cell", "knitsim arguments added",
         "CPU, all runs (s)", "wall, all runs (s)"],
        [[len(rows), manifest.get("seed", rows[0]["seed"] if rows else "—"),
          num(manifest["probability"] / 2) if "probability" in manifest else "—",
          "`%s`" % " ".join(manifest["knitsim_args"]) if manifest.get("knitsim_args") else "none",
          num(sum(cpu)), num(wall) if wall is not None else "—"]])
    refused = [r for r in rows if r["error"]]
    if refused:
        body += "\nRuns without results:\n\n" + md_table(
            ["chart", "status", "exit code", "message"],
            [[r["chart"], r["status"], r["exit_code"], r["error"]] for r in refused])
    return body


def distribution_section(rows):
    quantities = [
        ("minimum clearance over the run (r)", "clearance_min_over_r"),
        ("clearance at the end (r)", "clearance_end_over_r"),
        ("clearance at rest, t = 0 (r)", "clearance_rest_over_r"),
        ("resolution of the minimum (r)", "clearance_min_resolution_over_r"),
        ("crossings changed", "crossings_changed"),
        ("crossings designed", "crossings_designed"),
        ("largest displacement at the end (r)", "max_displacement_over_r"),
        ("Jacobian blocks outside the contact's fixed pattern", "pattern_misses"),
        ("CPU per chart, knitsim process (s)", "cpu_seconds"),
        ("of which clearance measuring (s)", "clearance_cpu_seconds"),
    ]
    table = []
    for label, key in quantities:
        vs = values(rows, key)
        if not vs:
            continue
        table.append([label, len(vs), num(min(vs)), num(percentile(vs, 25)), num(median(vs)),
                      num(percentile(vs, 75)), num(max(vs))])
    body = md_table(["quantity", "charts", "min", "25 %", "median", "75 %", "max"], table)

    def below(key):
        return sum(1 for v in values(rows, key) if v < WARN)

    measured = [r for r in rows if value(r, "clearance_min_over_r") is not None]
    changed = sum(1 for r in measured if (value(r, "crossings_changed") or 0) > 0)
    unresolved = sum(1 for v in values(rows, "clearance_min_resolution_over_r") if v > WARN)
    counts = [
        ["minimum clearance over the run < %s r" % num(WARN), below("clearance_min_over_r")],
        ["clearance at the end < %s r" % num(WARN), below("clearance_end_over_r")],
        ["clearance at rest (t = 0) < %s r" % num(WARN), below("clearance_rest_over_r")],
        ["a designed crossing changed", changed],
        ["resolution of the minimum > %s r (no guarantee between measured states)" % num(WARN),
         unresolved]]
    if values(rows, "pattern_misses"):  # runs with contact (older CSVs lack the column)
        counts.append(["a Jacobian block outside the contact's fixed pattern",
                       sum(1 for v in values(rows, "pattern_misses") if v > 0)])
    body += "\n" + md_table(["charts with", "of %d measured" % len(measured)], counts)
    return body


def feature_section(rows):
    """The rest clearance (and the run's) by the chart features that set it."""
    groups = [
        ("a miss directly above a tuck in its wale",
         lambda r: int(r["miss_over_tuck"]) > 0),
        ("else 3 or more tucks/misses on top of each other in one wale (longest_hold >= 3)",
         lambda r: int(r["longest_hold"]) >= 3),
        ("else 2 on top of each other (longest_hold = 2)", lambda r: int(r["longest_hold"]) == 2),
        ("else none on top of each other (longest_hold <= 1)", lambda r: True),
    ]
    left, table = list(rows), []
    for label, test in groups:
        members = [r for r in left if test(r)]
        left = [r for r in left if not test(r)]
        if not members:
            table.append([label, 0, "—", "—", "—", "—"])
            continue
        rest = values(members, "clearance_rest_over_r")
        mins = values(members, "clearance_min_over_r")
        ch = values(members, "crossings_changed")
        table.append([label, len(members),
                      span(rest),
                      num(median(mins)) if mins else "—", num(median(ch)) if ch else "—",
                      ", ".join(r["chart"] for r in sorted(
                          members, key=lambda r: value(r, "clearance_rest_over_r") or 0)[:WORST])
                      + (", …" if len(members) > WORST else "")])
    return md_table(["charts with (first matching row)", "charts", "clearance at rest (r)",
                     "median minimum clearance over the run (r)",
                     "median crossings changed", "lowest at rest"], table)


def worst_table(rows, key):
    ranked = sorted((r for r in rows if value(r, key) is not None),
                    key=lambda r: (value(r, key), r["chart"]))[:WORST]
    return md_table(
        ["chart", "tucks", "misses", "misses above a tuck", "longest hold", "status",
         "minimum clearance (r)", "at check", "at t (s)", "at the end (r)", "at rest (r)",
         "resolution (r)", "crossings changed", "CPU (s)"],
        [[r["chart"], r["tucks"], r["misses"], r["miss_over_tuck"], r["longest_hold"],
          r["status"], num(r["clearance_min_over_r"]), r.get("clearance_min_check") or "—",
          num(r["clearance_min_t"]),
          num(r["clearance_end_over_r"]), num(r["clearance_rest_over_r"]),
          num(r["clearance_min_resolution_over_r"]), crossings(r), num(r["cpu_seconds"])]
         for r in ranked])


def drawn_section(rows):
    ranked = sorted((r for r in rows if value(r, "clearance_min_over_r") is not None),
                    key=lambda r: (value(r, "clearance_min_over_r"), r["chart"]))
    if not ranked:
        return ""
    r = ranked[0]
    return ("Chart %s (the lowest minimum clearance; top course first, as in its .chart file):"
            "\n\n```\n%s\n```\n" % (r["chart"], "\n".join(r["rows"].split("/"))))


def build(folder):
    rows = read_rows(folder, CSV)
    manifest = read_json(folder, "manifest.json")
    if not rows:
        return ("Random charts", [CSV], [("No data", "no %s in %s\n" % (CSV, folder))])
    sections = [
        ("Runs (%s)" % CSV, runs_section(rows, manifest)),
        ("Distribution over the charts", distribution_section(rows)),
        ("Clearance at rest by chart feature", feature_section(rows)),
        ("Worst %d charts by minimum clearance over the run" % WORST,
         worst_table(rows, "clearance_min_over_r") + "\n" + drawn_section(rows)),
        ("Worst %d charts by clearance at rest (t = 0)" % WORST,
         worst_table(rows, "clearance_rest_over_r")),
        ("Provenance", provenance(manifest)),
    ]
    sources = [CSV, "manifest.json"]
    bare = read_rows(folder, BARE_CSV)
    if bare:
        bm = read_json(folder, BARE_MANIFEST)
        sections += [
            ("Without yarn contact: runs (%s)" % BARE_CSV, runs_section(bare, bm)),
            ("Without yarn contact: distribution over the charts", distribution_section(bare)),
            ("Without yarn contact: clearance at rest by chart feature", feature_section(bare)),
            ("Without yarn contact: worst %d charts by minimum clearance over the run" % WORST,
             worst_table(bare, "clearance_min_over_r") + "\n" + drawn_section(bare)),
            ("Without yarn contact: provenance", provenance(bm, BARE_MANIFEST)),
        ]
        sources += [BARE_CSV, BARE_MANIFEST]
    return ("Random 12 x 12 charts through `knitsim knit`", sources, sections)


if __name__ == "__main__":
    summary_main(STUDY, build)
