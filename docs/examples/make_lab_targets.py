#!/usr/bin/env python3
"""Writes docs/examples/lab_targets.csv: what four photos of a fabric hung from its four corners
give, in the target format of docs/fitting.md, from a knitsim drape of docs/examples/my_fabric.toml
(the "measured" fabric; k 600 N/m, L0 4 cm, topology a).

    docs/examples/make_lab_targets.py build/knitsim

Each edge is its own photo, taken from outside the sheet perpendicular to that edge: x to the
right along the edge, z UP, in mm, from an arbitrary camera origin; the two corner pins first
(A, then B), then every particle of the edge as a lab point, with seeded noise of 0.1 mm and
rounded to 0.1 mm like points read off a photo. Standard library only.
"""
import csv
import os
import random
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
knitsim = sys.argv[1] if len(sys.argv) > 1 else "build/knitsim"
scene = os.path.join(HERE, "my_fabric.toml")
out = tempfile.mkdtemp(prefix="lab-")
subprocess.run([knitsim, "drape", "--scene", scene, "--no-pictures", "--quiet", "--out", out],
               check=True)
nodes = {}
with open(os.path.join(out, "nodes.csv")) as f:
    for row in csv.DictReader(f):
        nodes[(int(row["i"]), int(row["j"]))] = (float(row["x"]), float(row["y"]), float(row["z"]))
n = max(i for i, _ in nodes)
# Edge: its particles from A to B, and the model axis along it (0 = x, 1 = y).
edges = {"top": ([(0, j) for j in range(n + 1)], 0),
         "bottom": ([(n, j) for j in range(n + 1)], 0),
         "left": ([(i, 0) for i in range(n + 1)], 1),
         "right": ([(i, n) for i in range(n + 1)], 1)}
rng = random.Random(7)
origin = {"top": (41.0, 312.5), "bottom": (18.5, 297.0), "left": (33.0, 305.5), "right": (27.5, 318.0)}
lines = ["# Lab data of a fabric hung from its four corners (docs/fitting.md): one photo per edge,",
         "# x to the right along the edge, z UP, mm from each photo's own origin; pins A then B.",
         "# Made by docs/examples/make_lab_targets.py from a knitsim drape of",
         "# docs/examples/my_fabric.toml (k 600 N/m, L0 0.04 m, topology a), noise 0.1 mm,",
         "# rounded to 0.1 mm. Fit it: knitsim fit --scene docs/examples/my_fabric.toml",
         "#   --target docs/examples/lab_targets.csv --optimizer lm",
         "scene,edge,kind,a,b"]
for name, (particles, axis) in edges.items():
    x0, z0 = origin[name]
    def camera(p, noise):
        x, z = nodes[p][axis] * 1000.0 + x0, nodes[p][2] * 1000.0 + z0
        if noise:
            x, z = x + rng.gauss(0.0, 0.1), z + rng.gauss(0.0, 0.1)
        return "%.1f" % x, "%.1f" % z
    for pin in (particles[0], particles[-1]):
        lines.append("four_corner,%s,pin,%s,%s" % ((name,) + camera(pin, False)))
    for p in particles:
        lines.append("four_corner,%s,lab_point,%s,%s" % ((name,) + camera(p, True)))
with open(os.path.join(HERE, "lab_targets.csv"), "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", os.path.join(HERE, "lab_targets.csv"))
