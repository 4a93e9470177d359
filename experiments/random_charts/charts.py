#!/usr/bin/env python3
"""Random stitch charts for `knitsim knit` (50 random 12 x 12 charts with ~10 % tucks
and misses, respecting the chart rules, seeded and reproducible by one command).

    charts.py [--count N] [--seed S] [--wales W] [--courses C] [--probability P] --out DIR

writes DIR/001.chart ... DIR/NNN.chart. Standard library only.

Rules (those models/knit_loops.hpp's KnitChart::validate enforces, no others): tucks and misses
in neither the bottom course nor an edge wale, no miss in the top course. Every other cell (an
"eligible" cell) is drawn independently: a tuck with probability P/2, a miss with P/2, else a
knit; in the top course a drawn miss stays a knit (the one cell kind where only the tuck is
allowed), so the top course has P/2 tucks and no misses. Stacked tucks, misses above or below a
tuck, floats over several wales and loops held over several courses all come out as the draw
gives them: the model accepts them.

Determinism: one random.Random(S) (Mersenne Twister; random() is the same on every platform and
Python 3 version) draws one number per eligible cell in a fixed order (charts in turn; in each,
courses bottom to top, wales left to right), every cell drawn whatever it becomes, so chart k is
the same for any N >= k: a --quick run's charts are the first ones of the full run.
"""
import argparse
import os
import random
import sys

WALES = 12
COURSES = 12
PROBABILITY = 0.10  # of a tuck or a miss in an eligible cell, half each


def generate(count, seed, wales=WALES, courses=COURSES, probability=PROBABILITY):
    """`count` charts as lists of courses (bottom course first), each a string of K/T/M per wale
    (leftmost first)."""
    if wales < 3 or courses < 2:
        raise ValueError("a chart with tucks or misses needs >= 3 wales and >= 2 courses")
    rng = random.Random(seed)
    charts = []
    for _ in range(count):
        grid = [["K"] * wales for _ in range(courses)]
        for j in range(1, courses):
            for i in range(1, wales - 1):
                u = rng.random()
                if u < probability / 2:
                    grid[j][i] = "T"
                elif u < probability and j < courses - 1:
                    grid[j][i] = "M"
        chart = ["".join(row) for row in grid]
        check_rules(chart)
        charts.append(chart)
    return charts


def check_rules(chart):
    """Raises ValueError when a chart (bottom course first) breaks a rule of the C++ model (the
    same rules as KnitChart::validate, row and column counted as drawn: top row 1, left
    column 1)."""
    courses, wales = len(chart), len(chart[0])
    for j, row in enumerate(chart):
        if len(row) != wales:
            raise ValueError("course %d has %d stitches, not %d" % (j, len(row), wales))
        for i, s in enumerate(row):
            where = "row %d, column %d" % (courses - j, i + 1)
            if s not in "KTM":
                raise ValueError("%s: %r is not a stitch" % (where, s))
            if s == "K":
                continue
            if j == 0 or i in (0, wales - 1):
                raise ValueError("%s: %s in the bottom course or an edge wale" % (where, s))
            if s == "M" and j == courses - 1:
                raise ValueError("%s: miss in the top course" % where)


def features(chart):
    """Counts of one chart (bottom course first): tucks, misses, the longest float (most misses
    next to each other in one course), the longest hold (most non-knits on top of each other in
    one wale: the loop below them is held over that many courses more), the highest stack of
    tucks in one hold (tucks between two knits of one wale, misses between them included:
    they hang from the same point) and how many misses lie directly above a tuck in its wale."""
    courses, wales = len(chart), len(chart[0])
    f = {"tucks": sum(r.count("T") for r in chart), "misses": sum(r.count("M") for r in chart),
         "longest_float": 0, "longest_hold": 0, "tuck_stack": 0,
         "miss_over_tuck": sum(1 for j in range(1, courses) for i in range(wales)
                               if chart[j][i] == "M" and chart[j - 1][i] == "T")}
    for row in chart:
        run = 0
        for s in row:
            run = run + 1 if s == "M" else 0
            f["longest_float"] = max(f["longest_float"], run)
    for i in range(wales):
        hold = stack = 0
        for j in range(courses):
            s = chart[j][i]
            hold, stack = (0, 0) if s == "K" else (hold + 1, stack + (s == "T"))
            f["longest_hold"] = max(f["longest_hold"], hold)
            f["tuck_stack"] = max(f["tuck_stack"], stack)
    return f


def drawn(chart):
    """The chart's rows as drawn (top course first)."""
    return list(reversed(chart))


def chart_text(chart, name, seed, probability=PROBABILITY):
    """The text of a .chart file: a comment line, then the rows as drawn."""
    f = features(chart)
    head = ("# random chart %s: seed %d, P(tuck) = P(miss) = %g per eligible cell; tucks %d, "
            "misses %d (experiments/random_charts/charts.py)\n"
            % (name, seed, probability / 2, f["tucks"], f["misses"]))
    return head + "\n".join(drawn(chart)) + "\n"


def write_charts(folder, count, seed, wales=WALES, courses=COURSES, probability=PROBABILITY):
    """Writes FOLDER/NNN.chart for the `count` charts; returns [(name, path, chart)]."""
    os.makedirs(folder, exist_ok=True)
    out = []
    for k, chart in enumerate(generate(count, seed, wales, courses, probability), start=1):
        name = "%03d" % k
        path = os.path.join(folder, name + ".chart")
        with open(path, "w") as fh:
            fh.write(chart_text(chart, name, seed, probability))
        out.append((name, path, chart))
    return out


def main():
    p = argparse.ArgumentParser(prog="experiments/random_charts/charts.py",
                                description="Write seeded random stitch charts.")
    p.add_argument("--count", type=int, default=50)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--wales", type=int, default=WALES)
    p.add_argument("--courses", type=int, default=COURSES)
    p.add_argument("--probability", type=float, default=PROBABILITY,
                   help="of a tuck or a miss per eligible cell (half each; default 0.1)")
    p.add_argument("--out", required=True, help="folder for NNN.chart")
    a = p.parse_args()
    for name, path, chart in write_charts(a.out, a.count, a.seed, a.wales, a.courses,
                                          a.probability):
        f = features(chart)
        print("%s: tucks %d, misses %d" % (path, f["tucks"], f["misses"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
