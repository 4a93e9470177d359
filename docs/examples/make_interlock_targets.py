#!/usr/bin/env python3
"""Writes docs/examples/interlock_targets.csv: an invented interlock hung from its four corners
(docs/fitting.md, "The material model"), whose course edges (top, bottom: along x) sag 22 mm and
wale edges (left, right: along y) 30 mm at mid-span, in the target format's normalised points.

    docs/examples/make_interlock_targets.py build/knitsim

The "measured" fabric is a knitsim drape of the material model (four_corner_material at 40 cells:
0.5 m square, 50 mm corner clamps, 41.65 g/m^2) with A_w = 24.87 N/m and A_c = 50.82 N/m (found
so that the mid-span sags are 22.0 and 30.0 mm), the rest the scene's. Each edge's every vertex is
a point (s, d) as src/measure/measurement.hpp normalises it (s along the edge from its first
corner, d the sag over the 0.5 m span), with seeded noise of 0.1 mm in d. Standard library only.
"""
import csv
import os
import random
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
knitsim = sys.argv[1] if len(sys.argv) > 1 else "build/knitsim"
sets = ["mesh.cells=40", "material.membrane_wale=24.87", "material.membrane_course=50.82"]
out = tempfile.mkdtemp(prefix="interlock-")
cmd = [knitsim, "drape", "--scene", "four_corner_material", "--no-pictures", "--quiet", "--out", out]
for s in sets:
    cmd += ["--set", s]
subprocess.run(cmd, check=True)
nodes = {}
with open(os.path.join(out, "nodes.csv")) as f:
    for row in csv.DictReader(f):
        nodes[(int(row["i"]), int(row["j"]))] = (float(row["x"]), float(row["y"]), float(row["z"]))
n = max(i for i, _ in nodes)
span = 0.5  # m: the corners are clamped at rest, so every edge's span is the side
edges = {"top": [(0, j) for j in range(n + 1)], "bottom": [(n, j) for j in range(n + 1)],
         "left": [(i, 0) for i in range(n + 1)], "right": [(i, n) for i in range(n + 1)]}
rng = random.Random(52)
lines = ["# An invented interlock (issue 52): course edges (top, bottom) sag 22 mm, wale edges (left,",
         "# right) 30 mm; normalised points of a material-model drape with 0.1 mm noise.",
         "# Made by docs/examples/make_interlock_targets.py: " + ", ".join(sets),
         "scene,edge,kind,a,b"]
for name, vertices in edges.items():
    a = nodes[vertices[0]]
    for v in vertices:
        p = nodes[v]
        along = (p[0] - a[0]) if name in ("top", "bottom") else (p[1] - a[1])
        s = along / span
        d = -p[2] / span + rng.gauss(0.0, 0.1e-3) / span
        lines.append(f"four_corner,{name},point,{s:.6f},{d:.7f}")
with open(os.path.join(HERE, "interlock_targets.csv"), "w") as f:
    f.write("\n".join(lines) + "\n")
mid = n // 2
print("mid-span sag, mm: top %.2f, left %.2f" % (-nodes[(0, mid)][2] * 1e3, -nodes[(mid, 0)][2] * 1e3))
