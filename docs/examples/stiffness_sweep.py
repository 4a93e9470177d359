#!/usr/bin/python3
"""A parameter sweep from Python (docs/python.md): the four_corner drape's centre sag against the
spring stiffness over the fit box of paper 1's Table 3 (500..1200 N/m), for topologies a and b,
with a matplotlib figure. Run headless by ctest python_module (tests/python/test_examples.py).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/stiffness_sweep.py [--out DIR] [--points N]

Writes DIR/sag_vs_stiffness.csv and DIR/sag_vs_stiffness.png (default DIR: out/examples).
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import knitsim  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.join("out", "examples"))
    p.add_argument("--points", type=int, default=15, help="stiffness values per topology")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)

    stiffness = np.linspace(500.0, 1200.0, a.points)  # N/m
    rows = []
    fig, ax = plt.subplots(figsize=(6, 4))
    for topology in ("a", "b"):
        sag = []
        for k in stiffness:
            r = knitsim.drape("four_corner", {"model.stiffness": k, "model.topology": topology})
            if r.status != "equilibrium":  # a status, not an exception: report and go on
                print("k = %g N/m, topology %s: %s (%s)" % (k, topology, r.status, r.message))
            sag.append(100 * r.centre_sag)  # cm
            rows.append(dict(topology=topology, stiffness_n_per_m=k, status=r.status,
                             centre_sag_m=r.centre_sag, max_strain=r.max_strain))
        ax.plot(stiffness, sag, "o-", label="topology " + topology)
    ax.set_xlabel("spring stiffness k (N/m)")
    ax.set_ylabel("centre sag (cm)")
    ax.set_title("four_corner drape: sag against stiffness")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "sag_vs_stiffness.png"), dpi=120)
    with open(os.path.join(a.out, "sag_vs_stiffness.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print("wrote %s/sag_vs_stiffness.png and .csv (%d drapes)" % (a.out, len(rows)))


if __name__ == "__main__":
    main()
