#!/usr/bin/python3
"""The mesh dimension of the material model (docs/material_drape.md, "Convergence").

    experiments/convergence/material_mesh.py [--quick] [--out DIR]   (KNITSIM: the binary,
                                                                     default build/knitsim)
    experiments/convergence/material_mesh.py --table CSV --out DIR   (the table from a CSV)

four_corner_material (a 50 x 50 cm sheet, four 5 cm corner clamps) at mesh.cells = n for
n = 10, 20, 40, 50, 80, 100, 160, 200 (--quick: 10, 20, 40), each by the default `equilibrium`
solver (every end state certified), and paper 1's four_corner at the same cell count
(model.natural_length = 0.5 m / n), both at model.symmetry = auto: the largest mirror group
each has (an eighth here, its equilibrium certified on the whole sheet). Writes
material_mesh.csv (model, n, h, the group integrated, centre sag, energy, largest strain,
largest strain at least clamps.size from the clamps, steps, CPU s) and material_mesh.md (the
table, the observed order p = log2((s_n - s_2n) / (s_2n - s_4n)) of each triple n, 2n, 4n
and its Richardson limit s_4n + (s_4n - s_2n) / (2^p - 1), for the sag, the energy and the
largest strain). --quick exits 1 if a material run is not certified or its sag's successive
differences do not shrink.
"""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(knitsim, scene, sets, out):
    cmd = [knitsim, "drape", "--scene", scene, "--quiet", "--no-pictures", "--out", out]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def triples(rows, key):
    by_n = {r["n"]: r[key] for r in rows if r[key] != ""}
    out = []
    for n in sorted(by_n):
        if 2 * n in by_n and 4 * n in by_n:
            a, b, c = by_n[n], by_n[2 * n], by_n[4 * n]
            if (a - b) * (b - c) > 0 and b != c:
                p = math.log2((a - b) / (b - c))
                out.append((n, p, c + (c - b) / (2 ** p - 1)))
            else:
                out.append((n, float("nan"), float("nan")))
    return out


def main():
    quick = "--quick" in sys.argv
    out = os.path.join(ROOT, "out", "experiments", "convergence")
    if "--out" in sys.argv:
        out = sys.argv[sys.argv.index("--out") + 1]
    os.makedirs(out, exist_ok=True)
    knitsim = os.environ.get("KNITSIM", os.path.join(ROOT, "build", "knitsim"))
    cells = [10, 20, 40] if quick else [10, 20, 40, 50, 80, 100, 160, 200]
    work = tempfile.mkdtemp(prefix="material_mesh_")
    rows = []
    if "--table" in sys.argv:  # the table again from a material_mesh.csv, nothing run
        with open(sys.argv[sys.argv.index("--table") + 1]) as f:
            rows = [{k: (v if k in ("model", "symmetry", "status", "certificate") or v == ""
                         else int(v) if k in ("n", "steps") else float(v))
                     for k, v in r.items()} for r in csv.DictReader(f)]
        cells = []
    for n in cells:
        m = run(knitsim, "four_corner_material", [f"mesh.cells={n}"], os.path.join(work, f"m{n}"))
        rows.append({"model": "material", "n": n, "h_m": 0.5 / n,
                     "symmetry": m.get("symmetry", "none"), "status": m["status"],
                     "certificate": m.get("certificate", ""), "centre_sag_m": m["centre_sag_m"],
                     "energy_J": m["energy_J"], "max_strain": m["max_strain"],
                     "max_strain_away": m["max_strain_away_from_clamps"],
                     "steps": m["steps"], "cpu_s": m["cpu_seconds"]})
        p = run(knitsim, "four_corner", [f"model.natural_length={0.5 / n!r}"],
                os.path.join(work, f"p{n}"))
        rows.append({"model": "paper", "n": n, "h_m": 0.5 / n,
                     "symmetry": p.get("symmetry", "none"), "status": p["status"],
                     "certificate": p.get("certificate", ""), "centre_sag_m": p["centre_sag_m"],
                     "energy_J": "", "max_strain": p["max_strain"], "max_strain_away": "", "steps": p["steps"],
                     "cpu_s": p["cpu_seconds"]})
        print(f"n = {n}: material sag {m['centre_sag_m']:.6e} m, paper {p['centre_sag_m']:.6e} m",
              flush=True)
    fields = list(rows[0].keys())
    with open(os.path.join(out, "material_mesh.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    lines = ["# The mesh dimension: material model and paper 1's, four corners, 50 x 50 cm", "",
             "| model | n | h (mm) | group | status | centre sag (mm) | energy (mJ) | max strain (%) | "
             "away from the clamps (%) | steps | CPU s |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        e = "" if r["energy_J"] == "" else f"{1e3 * r['energy_J']:.6f}"
        a = "" if r["max_strain_away"] == "" else f"{100 * r['max_strain_away']:.5f}"
        lines.append(f"| {r['model']} | {r['n']} | {1e3 * r['h_m']:.2f} | {r.get('symmetry', '')} | {r['status']} "
                     f"({r['certificate']}) | {1e3 * r['centre_sag_m']:.5f} | {e} | "
                     f"{100 * r['max_strain']:.4f} | {a} | {r['steps']} | {r['cpu_s']:.2f} |")
    lines += ["", "Observed order p of the triple n, 2n, 4n and its Richardson limit:", "",
              "| model | quantity | n, 2n, 4n | p | limit |", "|---|---|---|---|---|"]
    for model in ("material", "paper"):
        sub = [r for r in rows if r["model"] == model]
        for key, scale, unit in (("centre_sag_m", 1e3, "mm"), ("energy_J", 1e3, "mJ"),
                                 ("max_strain", 100, "%"), ("max_strain_away", 100, "%")):
            for n, p, lim in triples(sub, key):
                # No limit to extrapolate where the differences change sign or do not shrink.
                limit = (f"{scale * lim:.6f} {unit}" if p > 0
                         else "none (the differences change sign)" if math.isnan(p)
                         else "none (the differences grow)")
                lines.append(f"| {model} | {key} | {n}, {2 * n}, {4 * n} | {p:.3f} | {limit} |")
    with open(os.path.join(out, "material_mesh.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    if quick:
        mat = [r for r in rows if r["model"] == "material"]
        bad = [r for r in mat if r["status"] != "equilibrium" or r["certificate"] != "stable_minimum"]
        s = [r["centre_sag_m"] for r in mat]
        if bad or not abs(s[2] - s[1]) < abs(s[1] - s[0]):
            print("FAIL: a material run not certified, or its sag's differences do not shrink")
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
