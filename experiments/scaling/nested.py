"""Coarse-to-fine start (nested iteration) for the scaling study's four_corner sheet.

Question: does starting a fine grid from the interpolated equilibrium of the grid with half
as many cells per side reach the same equilibrium as the drape from the flat sheet, and how
much cheaper is it?  Two routes per fine grid n (cells per side, even):

  flat    knitsim drape ... --integrator static                   (the reference)
  nested  the same drape at n/2 (static, from flat), its nodes interpolated bilinearly onto
          the n grid (coarse node (i, j) -> fine node (2i, 2j), the others between), written
          as the state.json of the fine model (v = 0, at the coarse run's t_final, after the
          pins stopped moving), then knitsim drape ... --integrator static --continue.

The sheet, L0 = 0.5 m / n and the damping scaled with the particle mass are those of
experiments/scaling/run.sh, on the full grid (the interpolation needs every node integrated).
Writes OUT/nested_runs.csv (one row per route and grid; cpu_seconds of the nested route is
the coarse run's plus the fine run's solver CPU; start_residual the static residual after the
first step, from --step-history) and OUT/nested_manifest.json.

    /usr/bin/python3 experiments/scaling/nested.py [--quick] [--grids "50 100"]
                                                    [--out DIR] [--keep-runs]

Exit status 1 if a route did not reach equilibrium.
"""
import csv
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

WIDTH = 0.5  # m, the sheet of the scaling study


def model_args(n):
    """--set flags of the scaling study's grid with n cells per side."""
    length = WIDTH / n
    damping = 12.0 * (length / 0.049) ** 2
    return ["--set", "model.natural_length=%r" % length, "--set", "model.damping=%r" % damping]


def read_nodes(folder):
    """nodes.csv as rows {id, i, j, x, y, z, pinned} in id order."""
    rows = list(csv.DictReader(open(os.path.join(folder, "nodes.csv"))))
    return sorted(rows, key=lambda r: int(r["id"]))


def prolong(coarse, template, folder):
    """Write folder/state.json (and the template's manifest.json): the template run's state (the
    fine model, its keys and layout) with x = the coarse run's equilibrium interpolated
    bilinearly, v = 0, t = coarse t_final.
    The integrated coordinates are those of the unpinned nodes in id order (as write_run_state
    writes them); the length is checked against the template's."""
    pos = {(int(r["i"]), int(r["j"])): [float(r[k]) for k in "xyz"] for r in read_nodes(coarse)}
    nc = max(i for i, _ in pos)
    fine = read_nodes(template)
    nf = max(int(r["i"]) for r in fine)
    if nf != 2 * nc:
        sys.exit("nested: fine grid %d is not twice the coarse %d" % (nf, nc))
    x = []
    for r in fine:
        if r["pinned"] == "1":
            continue
        i, j = int(r["i"]), int(r["j"])
        i0, j0, fi, fj = i // 2, j // 2, (i % 2) / 2.0, (j % 2) / 2.0
        i1, j1 = min(i0 + 1, nc), min(j0 + 1, nc)
        p = [0.0, 0.0, 0.0]
        for a, b, w in ((i0, j0, (1 - fi) * (1 - fj)), (i1, j0, fi * (1 - fj)),
                        (i0, j1, (1 - fi) * fj), (i1, j1, fi * fj)):
            if w > 0.0:
                p = [u + w * v for u, v in zip(p, pos[(a, b)])]
        x += p
    state = json.load(open(os.path.join(template, "state.json")))
    if len(x) != state["integrated_dof"]:
        sys.exit("nested: %d interpolated coordinates, the fine model integrates %d"
                 % (len(x), state["integrated_dof"]))
    state["x"] = x
    state["v"] = [0.0] * len(x)
    state["t"] = json.load(open(os.path.join(coarse, "state.json")))["t"]
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "state.json"), "w") as f:
        json.dump(state, f)
    # --continue takes only a folder whose set of files is complete, marked by its manifest
    # (written last): the template's, which describes the same fine model and options.
    shutil.copyfile(os.path.join(template, "manifest.json"), os.path.join(folder, "manifest.json"))


def first_residual(run):
    """The static residual after the run's first step (steps.csv, --step-history)."""
    with open(os.path.join(run.folder, "steps.csv")) as f:
        return float(next(csv.DictReader(f))["residual"])


def row(n, route, run, cpu, reference):
    s = run.stats()
    return {"n": n, "particles": (n + 1) ** 2, "route": route, "status": s.get("status"),
            "steps": s.get("steps"), "factorisations": s.get("factorisations"),
            "t_final": s.get("t_final"), "residual": s.get("residual"),
            "centre_sag_m": s.get("centre_sag_m"), "cpu_seconds": cpu,
            "start_residual": first_residual(run),
            "max_position_difference_m":
                expkit.max_position_error(expkit.read_positions(run),
                                          expkit.read_positions(reference))}


def main():
    def extra(p):
        p.add_argument("--grids", default=None, help='fine grids, cells per side (even), '
                       'default "50 100" ("20" with --quick)')
    args = expkit.parse_args("scaling", "scaling-nested", extra)
    grids = [int(g) for g in (args.grids or ("20" if args.quick else "50 100")).split()]
    if any(g < 4 or g % 2 for g in grids):
        sys.exit("nested: --grids must be even numbers of cells per side >= 4")
    common = ["drape", "--scene", "four_corner", "--integrator", "static", "--no-pictures",
              "--step-history"]
    rows = []
    for n in grids:
        fine = common + model_args(n)
        flat = expkit.run_knitsim(args.out, "%d-flat" % n, fine)
        coarse = expkit.run_knitsim(args.out, "%d-coarse" % n, common + model_args(n // 2))
        template = expkit.run_knitsim(args.out, "%d-template" % n, fine + ["--max-steps", "1"])
        start = os.path.join(args.out, "runs", "%d-start" % n)
        shutil.rmtree(start, ignore_errors=True)
        prolong(coarse.folder, template.folder, start)
        nested = expkit.run_knitsim(args.out, "%d-nested" % n, fine + ["--continue", start])
        rows.append(row(n, "flat", flat, flat.stats()["cpu_seconds"], flat))
        rows.append(row(n, "nested", nested,
                        coarse.stats()["cpu_seconds"] + nested.stats()["cpu_seconds"], flat))
        rows[-1]["coarse_cpu_seconds"] = coarse.stats()["cpu_seconds"]
        for r in rows[-2:]:
            print("n=%d %-6s %s steps %s factorisations %s cpu %.3f s  max |dx| vs flat %.2g m"
                  % (n, r["route"], r["status"], r["steps"], r["factorisations"],
                     r["cpu_seconds"], r["max_position_difference_m"]))
    expkit.write_csv(os.path.join(args.out, "nested_runs.csv"), rows,
                     list(rows[0].keys()) + ["coarse_cpu_seconds"])
    command = " ".join(["/usr/bin/python3 experiments/scaling/nested.py"] + sys.argv[1:])
    expkit.write_manifest(args, "scaling", extra={"study": "nested start", "grids": grids,
                                                   "command": command})
    os.replace(os.path.join(args.out, "manifest.json"),
               os.path.join(args.out, "nested_manifest.json"))
    expkit.finish(args)
    return 0 if all(r["status"] == "equilibrium" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
