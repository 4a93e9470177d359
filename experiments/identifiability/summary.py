#!/usr/bin/python3
"""Tables of experiments/identifiability from its CSV files only (identifiability.csv,
profiles.csv, manifest.json of build/knitsim_identifiability; the true L0 of each twin sample
from the header of its committed target, paper_repro/data/targets/<set>_sample<s>.csv)
-> summary.md; the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/identifiability)
"""
import math
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from expkit import (ROOT, md_table, num, provenance, read_json, read_rows, span,  # noqa: E402
                    summary_main)

WIDTH = 0.50  # m: the sheet's side; the grid has n = round(W / L0) cells per side
TARGETS = os.path.join(ROOT, "paper_repro", "data", "targets")


def cells(natural_length):
    """n = round(W / L0), halves rounded up (std::round)."""
    return int(math.floor(WIDTH / natural_length + 0.5))


def true_length(set_name, sample):
    """The true L0 (m) from the '# Sample:' header line of the committed target, or None."""
    path = os.path.join(TARGETS, "%s_sample%s.csv" % (set_name, sample))
    if not os.path.exists(path):
        return None
    with open(path) as f:
        for line in f:
            m = re.search(r"natural_length ([0-9.eE+-]+) m", line)
            if line.startswith("#") and m:
                return float(m.group(1))
    return None


def percent(x):
    return "%s %%" % num(100 * float(x), 3)


def build(out):
    ident = read_rows(out, "identifiability.csv")
    prof = read_rows(out, "profiles.csv")
    sections = []
    rows = []
    info = []
    for r in ident:
        L0 = true_length(r["set"], r["sample"])
        n_true = cells(L0) if L0 else None
        valley = [p for p in prof if (p["set"], p["sample"], p["data"]) ==
                  (r["set"], r["sample"], r["data"])
                  and p["parameter"] == "natural_length_at_fixed_ratio"
                  and math.isfinite(float(p["objective"]))]
        best = min(valley, key=lambda p: float(p["objective"])) if valley else None
        n_best = cells(float(best["value"])) if best else None
        info.append((r, n_true, n_best))
        rows.append([r["sample"], n_true if n_true else "—", r["data"],
                     num(r["objective_at_truth"], 3), r["rank"],
                     percent(r["k_over_L0_rel_error"]), percent(r["cse_k_rel"]),
                     num(r["corr_k_L0"], 3),
                     "%d (%s)" % (n_best, num(best["objective"], 3)) if best else "—"])
    sets = sorted({r["set"] for r in ident})
    sections.append((
        "Per sample and data set (identifiability.csv, profiles.csv)",
        "At the twin's true parameters: the objective E (Eq. 5, %%), the rank of J = dr/dp, the "
        "relative standard error of k/L0 and of k with L0 known, corr(k, L0); \"best n\" = the "
        "grid size n = round(W/L0) whose bracket holds the lowest objective of the "
        "`natural_length_at_fixed_ratio` slice (k/L0 held at the truth), with that objective. "
        "True n from the true L0 in the header of the committed target (%s).\n\n"
        % ", ".join("`paper_repro/data/targets/%s_sample<s>.csv`" % s for s in sets)
        + md_table(["sample", "true n", "data", "E at truth %", "rank", "k/L0 rel. SE",
                    "k rel. SE (L0 known)", "corr(k, L0)", "best n along the k/L0 valley (E %)"],
                   rows)))

    agg = []
    for data in dict.fromkeys(r["data"] for r in ident):
        mine = [x for x in info if x[0]["data"] == data]
        rs = [x[0] for x in mine]
        known = [x for x in mine if x[1] is not None]
        hits = [x for x in known if x[1] == x[2]]
        misses = [x[0]["sample"] for x in known if x[1] != x[2]]
        agg.append([data, len(rs), ", ".join(sorted({r["rank"] for r in rs})),
                    ", ".join(sorted({num(r["corr_k_L0"], 3) for r in rs})),
                    "%d of %d" % (sum(r["se_k_rel"] == "inf" and r["se_L0_rel"] == "inf"
                                      for r in rs), len(rs)),
                    "%d of %d" % (sum(r["damping_zero"] == "1" and r["elongation_zero"] == "1"
                                      for r in rs), len(rs)),
                    span([100 * float(r["k_over_L0_rel_error"]) for r in rs],
                         lambda v: num(v, 3)) + " %",
                    span([r["objective_at_truth"] for r in rs], lambda v: num(v, 3)) + " %",
                    "%d of %d%s" % (len(hits), len(known),
                                    " (not %s)" % ", ".join(misses) if misses else "")])
    sections.append((
        "What the edges determine, over the samples",
        md_table(["data", "samples", "rank", "corr(k, L0)", "k and L0 separately: SE inf",
                  "damping and ε: zero columns", "k/L0 rel. SE", "E at truth",
                  "true n = best n of the valley"], agg)))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return ("identifiability: tables", ["identifiability.csv", "profiles.csv", "manifest.json"],
            sections)


def main(argv=None):
    return summary_main("identifiability", build, argv)


if __name__ == "__main__":
    main()
