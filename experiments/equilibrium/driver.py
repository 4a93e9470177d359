"""The equilibrium solver against the dynamics (experiments/equilibrium/README.md).

cost.csv: per (scene, grid, integrator) `repeats` runs of `knitsim drape --no-pictures`, each
run's own CPU seconds (summary.json cpu_seconds: the solve, without start-up and outputs),
steps, factorisations, status and certificate.
random.csv: drapes drawn from paper 1's Table 3 box (stiffness 500-1200 N/m, damping 10-20 N s/m,
elongation limit 5-20 %, L0 4-6 cm, topology a/b/c, an areal density of Table 2), each run by
the default solver and by cvode-bdf at rtol 1e-10 (the reference): status, certificate, and the
largest distance between the two (m) where both settle.
"""
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

NAME = "equilibrium"


def add_arguments(p):
    p.add_argument("--repeats", type=int, help="runs per cost row (default 15, quick 5)")
    p.add_argument("--random", type=int, help="random drapes per scene (default 100, quick 5)")


def drape(out, label, scene, integrator, sets, extra=()):
    args = ["drape", "--scene", scene, "--integrator", integrator, "--no-pictures"]
    for s in sets:
        args += ["--set", s]
    return expkit.run_knitsim(out, label, args + list(extra))


def main():
    a = expkit.parse_args(NAME, NAME, add_arguments)
    repeats = a.repeats or (5 if a.quick else 15)
    n_random = a.random if a.random is not None else (5 if a.quick else 100)
    rows = []
    # The built-in meshes (L0 5 cm: 11 x 11 particles), and refined four_corner sheets
    # (W = 0.5 m: L0 5 mm is 101 x 101 particles, 2.5 mm 201 x 201).
    grids = [("four_corner", ""), ("two_corner", "")]
    if not a.quick:
        grids += [("four_corner", "0.005"), ("four_corner", "0.0025")]
    integrators = [("equilibrium", []), ("cvode-bdf", []), ("implicit-euler", ["--dt", "100"])]
    for scene, l0 in grids:
        for integ, extra in integrators:
            fine = l0 != ""
            if fine and integ == "implicit-euler":
                continue
            if l0 == "0.0025" and integ != "equilibrium":
                continue
            n = 1 if (fine and integ != "equilibrium") or l0 == "0.0025" else (3 if fine else repeats)
            for k in range(n):
                label = "%s_%s_%s_%d" % (scene, l0, integ, k)
                sets = ["model.symmetry=none"] + (["model.natural_length=" + l0] if l0 else [])
                r = drape(a.out, label, scene, integ, sets,
                          list(extra) + (["--max-wall", "900"] if fine else []))
                s = r.stats()
                rows.append({"scene": scene, "natural_length": l0 or "0.05",
                             "particles": s["grid"]["particles"],
                             "integrator": integ + (" --dt 100" if extra else ""), "repeat": k,
                             "status": s["status"], "certificate": s.get("certificate", ""),
                             "steps": s["steps"], "factorisations": s["factorisations"],
                             "stop_factorisations": s.get("stop_factorisations", 0),
                             "cpu_seconds": s["cpu_seconds"]})
                print("%-12s L0 %-6s %-22s %s %s %.4f s" % (scene, l0, rows[-1]["integrator"],
                                                           s["status"], rows[-1]["certificate"],
                                                           s["cpu_seconds"]))
    expkit.write_csv(os.path.join(a.out, "cost.csv"), rows)

    rng = random.Random(29)
    rand_rows = []
    for scene in ("four_corner", "two_corner"):
        for i in range(n_random):
            p = {"model.stiffness": rng.uniform(500, 1200), "model.damping": rng.uniform(10, 20),
                 "model.elongation_limit": rng.uniform(5, 20),
                 "model.natural_length": rng.uniform(0.04, 0.06),
                 "model.topology": "abc"[rng.randrange(3)],
                 "fabric.areal_density": rng.choice([27.6, 41.65, 58.26])}
            sets = ["%s=%s" % (k, repr(v) if isinstance(v, float) else v) for k, v in p.items()]
            sets.append("model.symmetry=none")
            eq = drape(a.out, "r_%s_%d_eq" % (scene, i), scene, "equilibrium", sets)
            ref = drape(a.out, "r_%s_%d_ref" % (scene, i), scene, "cvode-bdf", sets,
                        ["--rtol", "1e-10"])
            se, sr = eq.stats(), ref.stats()
            both = se["status"] == "equilibrium" and sr["status"] == "equilibrium"
            row = dict(p)
            row.update({"scene": scene, "index": i, "status": se["status"],
                        "certificate": se.get("certificate", ""),
                        "message": se.get("message", ""),
                        "cpu_seconds": se["cpu_seconds"], "reference_status": sr["status"],
                        "reference_cpu_seconds": sr["cpu_seconds"],
                        "distance_m": expkit.max_position_error(expkit.read_positions(eq),
                                                                  expkit.read_positions(ref))
                        if both else ""})
            rand_rows.append(row)
    expkit.write_csv(os.path.join(a.out, "random.csv"), rand_rows)
    expkit.write_manifest(a, NAME, extra={"repeats": repeats, "random": n_random, "seed": 29})
    expkit.finish(a)


if __name__ == "__main__":
    main()
