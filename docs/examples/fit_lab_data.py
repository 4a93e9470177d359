#!/usr/bin/python3
"""A fit to the lab-data example from Python (docs/python.md, docs/fitting.md): the ICA fits
my_fabric.toml's drape to lab_targets.csv, then the fitted drape's edges are plotted against the
target's. Run headless by ctest python_module (tests/python/test_examples.py).

    PYTHONPATH=build/python /usr/bin/python3 docs/examples/fit_lab_data.py [--out DIR] [--decades N]

Writes DIR/fit_edges.png and DIR/fitted_drape/ (the files of `knitsim drape`; default DIR:
out/examples).
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import knitsim  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.join("out", "examples"))
    p.add_argument("--decades", type=int, default=10, help="ICA decades (the paper's: 40)")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)

    f = knitsim.fit(os.path.join(HERE, "lab_targets.csv"), os.path.join(HERE, "my_fabric.toml"),
                    decades=a.decades, countries=15, seed=1)
    print(f)
    print("fitted:", ", ".join("%s %s" % kv for kv in f.params.items()))
    drape = f.drape
    drape.write(os.path.join(a.out, "fitted_drape"), pictures=False)

    s = np.linspace(0.0, 1.0, 101)
    fig, axes = plt.subplots(2, 2, figsize=(8, 6), sharex=True)
    fitted = drape.summary["edge_coefficients"]
    target = drape.summary["target_edge_coefficients"]
    for ax, name in zip(axes.ravel(), sorted(fitted)):
        edge = drape.edges[name]
        ax.plot(edge["s"], edge["d"], "k.", ms=3, label="fitted drape's nodes")
        ax.plot(s, np.polyval(fitted[name][::-1], s), "b-", label="fitted edge")
        ax.plot(s, np.polyval(target[name][::-1], s), "r--", label="lab target")
        ax.set_title(name)
        ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("s (along the edge, normalised)")
    for ax in axes[:, 0]:
        ax.set_ylabel("d (sag of the edge, normalised)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("fit to lab_targets.csv: Eq. 5 error %.3g %%" % f.objective)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "fit_edges.png"), dpi=110)
    print("wrote %s/fit_edges.png" % a.out)


if __name__ == "__main__":
    main()
