"""Convergence figures from the CSV files of driver.py in DIR; reads nothing else.

  /usr/bin/python3 experiments/convergence/plot.py DIR

Writes DIR/convergence.png, four panels: (a) fixed-step error at t_end vs dt with the fitted
slopes and reference slopes 1 and 2; (b) adaptive error at t_end vs rtol; (c) mesh refinement:
centre sag and edge-coefficient difference to the finest mesh vs L0; (d) ICA best cost vs
evaluations, one line per seed.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]


def read(name):
    path = os.path.join(out, name)
    if not os.path.exists(path):
        return []
    rows = list(csv.DictReader(open(path)))
    for r in rows:
        for k, v in r.items():
            try:
                r[k] = float(v)
            except ValueError:
                pass
    return rows


orders, fits = read("orders.csv"), {r["integrator"]: r for r in read("orders_fit.csv")}
tol, tol_fit = read("tolerance.csv"), {r["integrator"]: r for r in read("tolerance_fit.csv")}
mesh, ica = read("mesh.csv"), read("ica.csv")
fig, ax = plt.subplots(2, 2, figsize=(12, 9))

a = ax[0][0]
for name in dict.fromkeys(r["integrator"] for r in orders):
    rs = [r for r in orders if r["integrator"] == name]
    a.loglog([r["dt"] for r in rs], [r["error_m"] for r in rs], "o-",
             label="%s: slope %.2f" % (name, fits[name]["fitted"]))
for p, ls in ((1, ":"), (2, "--")):
    x0 = min(r["dt"] for r in orders)
    x1 = max(r["dt"] for r in orders)
    y0 = min(r["error_m"] for r in orders)
    a.loglog([x0, x1], [y0, y0 * (x1 / x0) ** p], "k" + ls, lw=0.8, label="slope %d" % p)
a.set_xlabel("dt (s)")
a.set_ylabel("max position error at t_end (m)")
a.set_title("(a) fixed-step methods, four_corner trajectory")
a.legend(fontsize=8)
a.grid(True, alpha=0.3)

a = ax[0][1]
for name in dict.fromkeys(r["integrator"] for r in tol):
    rs = [r for r in tol if r["integrator"] == name and r["error_m"] > 0]
    a.loglog([r["rtol"] for r in rs], [r["error_m"] for r in rs], "o-",
             label="%s: slope %.2f" % (name, tol_fit[name]["slope"]))
a.set_xlabel("rtol (atol = 1e-3 rtol)")
a.set_ylabel("max position error at t_end (m)")
a.set_title("(b) adaptive methods vs tolerance")
a.legend(fontsize=7)
a.grid(True, alpha=0.3)

a = ax[1][0]
l0 = [100 * r["natural_length_m"] for r in mesh]
a.semilogx(l0, [100 * r["centre_sag_m"] for r in mesh], "o-", label="centre sag (cm)")
a.set_xlabel("L0 (cm)")
a.set_ylabel("centre sag (cm)")
b = a.twinx()
rs = mesh[:-1]
b.loglog([100 * r["natural_length_m"] for r in rs], [r["sag_diff_to_finest_m"] * 100 for r in rs],
         "s--", color="C1", label="|sag - finest| (cm)")
b.loglog([100 * r["natural_length_m"] for r in rs], [r["coeff_diff_to_finest_pct"] for r in rs],
         "^--", color="C2", label="edge coefficients vs finest, Eq. 5 (%)")
b.set_ylabel("difference to the finest mesh")
h1, l1 = a.get_legend_handles_labels()
h2, l2 = b.get_legend_handles_labels()
a.legend(h1 + h2, l1 + l2, fontsize=8, loc="upper left")
a.set_title("(c) four_corner mesh refinement (c scaled with particle mass)")
a.grid(True, alpha=0.3)

a = ax[1][1]
problems = list(dict.fromkeys(r["problem"] for r in ica))
for k, problem in enumerate(problems):
    for j, seed in enumerate(dict.fromkeys(r["seed"] for r in ica if r["problem"] == problem)):
        rs = [r for r in ica if r["problem"] == problem and r["seed"] == seed]
        a.semilogy([r["evaluations"] for r in rs], [max(r["best"], 1e-12) for r in rs], "-",
                   color="C%d" % k, lw=1, alpha=0.8,
                   label="%s (dim %d)" % (problem, rs[0]["dim"]) if j == 0 else None)
a.set_xlabel("evaluations")
a.set_ylabel("best cost")
a.set_title("(d) ICA best cost vs evaluations (one line per seed)")
a.legend(fontsize=8)
a.grid(True, alpha=0.3)

fig.tight_layout()
fig.savefig(os.path.join(out, "convergence.png"), dpi=110)
print("convergence: wrote %s/convergence.png" % out)

# The tables of the README (summary.md) from the same CSV files.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import summary  # noqa: E402

summary.main([out])
