#!/usr/bin/python3
"""A knit chart relaxed from Python (docs/python.md): the chart's interlacing-point network run to
its steady state, its loops (each course's yarn centreline) plotted at rest and relaxed in the
front view, and the loop heights of stitches.csv summed up per stitch type. Run headless by
ctest python_module (tests/python/test_examples.py).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/knit_loops.py [--chart FILE] [--out DIR]

Writes DIR/knit_loops.png and DIR/knit_loops.csv (default chart models/charts/single_tuck.chart,
default DIR out/examples).
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import knitsim  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--chart", default=os.path.join(ROOT, "models", "charts", "single_tuck.chart"))
    p.add_argument("--out", default=os.path.join("out", "examples"))
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)

    r = knitsim.knit(a.chart)
    print("%s: %s (%s), %d points, max displacement %.3g r" %
          (r.chart, r.status, r.integrator, len(r.positions),
           r.summary["max_displacement_over_r"]))

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5), sharex=True, sharey=True)
    for ax, lines, points, title in (
            (axes[0], r.rest_centerlines, r.rest_positions, "at rest"),
            (axes[1], r.centerlines, r.positions, r.status)):
        for c, line in enumerate(lines):  # one yarn per course, bottom first
            ax.plot(1e3 * line[:, 0], 1e3 * line[:, 1], lw=1.2,
                    color="tab:red" if c % 2 == 0 else "tab:blue")
        ax.plot(1e3 * points[:, 0], 1e3 * points[:, 1], ".", ms=2, color="k")
        ax.set_title("%s: %s" % (r.chart, title))
        ax.set_xlabel("x (mm)")
        ax.set_aspect("equal")
    axes[0].set_ylabel("y (mm)")
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "knit_loops.png"), dpi=120)

    # Loop heights by stitch type (NaN where a cell has no loop: a miss).
    s = r.stitches
    rows = []
    for stitch in sorted(set(s["stitch"].tolist())):
        pick = s["stitch"] == stitch
        h, h0 = s["loop_height_m"][pick], s["loop_height0_m"][pick]
        mean = lambda v: float(np.nanmean(v)) if np.isfinite(v).any() else ""  # noqa: E731
        rows.append(dict(stitch=stitch, cells=int(pick.sum()), mean_loop_height_m=mean(h),
                         mean_loop_height0_m=mean(h0)))
    with open(os.path.join(a.out, "knit_loops.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for row in rows:
        print("stitch %(stitch)s: %(cells)d cells, mean loop height %(mean_loop_height_m)s m "
              "(rest %(mean_loop_height0_m)s m)" % row)


if __name__ == "__main__":
    main()
