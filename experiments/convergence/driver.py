"""Convergence study, four parts, all through the knitsim CLI:

  orders     observed order of the fixed-step methods (euler, verlet, implicit-euler) from a
             step-halving series on a short trajectory of the four_corner drape, t_end = 4e-5 s
             (five time constants m/c of the damping transient that follows the release; later
             the sheet creeps so smoothly that every method's error is round-off): the run stops
             at t_end = run.t_max (the driver never steps past t_max, so every run ends exactly
             there), error = max over particles of |x(t_end) - x_ref(t_end)|, reference cvode-bdf
             at rtol 1e-12; least-squares slope of log error vs log dt.
  tolerance  error at t_end of every adaptive integrator vs rtol (atol = 1e-3 rtol), same
             reference; slope of log error vs log rtol (1 = tolerance proportionality).
  mesh       four_corner equilibrium under mesh refinement, L0 = W/n for n = 8..50 (6.25 cm to
             1 cm): centre sag and Eq. 5 edge coefficients; damping scaled with the particle
             mass, c = 12 N s/m x (L0 / 4.9 cm)^2, so c/m (and the settling time) stays that of
             the default mesh: the equilibrium does not depend on c.
  ica        best cost vs evaluations of `knitsim optimize` (ICA, default settings) on
             rastrigin and rosenbrock, several seeds; in full mode also `knitsim fit` on
             four_corner against the default drape's own edges (known answer, cost 0).

Outputs in --out: orders.csv, orders_fit.csv, tolerance.csv, tolerance_fit.csv, mesh.csv,
ica.csv, manifest.json. Called by run.sh; see README.md.
"""
import csv
import math
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

SCENE = "four_corner"
REF = dict(rtol=1e-12, atol=1e-16)
EXPECTED_ORDER = {"euler": 1, "verlet": 2, "implicit-euler": 1}
ORDER_TOLERANCE = 0.25  # CI check: |observed - expected| <= this
W = 0.5                 # m, fabric width of the built-in scenes
L0_DEFAULT, C_DEFAULT = 0.049, 12.0


def plan(quick):
    n = [40, 80, 160] if quick else [40, 80, 160, 320, 640]
    common = dict(t_end=4e-5, steps={"euler": n, "verlet": n, "implicit-euler": n})
    if quick:
        return dict(common, rtols=[1e-3, 1e-5, 1e-7], tol_integrators=["cvode-bdf", "arkode-dirk"],
                    mesh_n=[8, 10, 16, 20], ica_problems=["rastrigin"], ica_seeds=[1, 2],
                    fit_seeds=[])
    return dict(common, rtols=[10.0 ** -e for e in range(3, 11)], tol_integrators=None,
                mesh_n=[8, 10, 12, 16, 20, 24, 32, 40, 50],
                ica_problems=["rastrigin", "rosenbrock"], ica_seeds=[1, 2, 3, 4, 5],
                fit_seeds=[1, 2, 3])


def main():
    args = expkit.parse_args("convergence", "convergence")
    p = plan(args.quick)
    out = args.out
    failures = []

    def trajectory(label, t_end, extra):
        r = expkit.run_knitsim(out, label, ["drape", "--scene", SCENE, "--set",
                                            "run.t_max=%r" % t_end] + extra)
        s = r.stats()
        if s.get("status") != "time_limit" or abs(s["t_final"] - t_end) > 1e-12 * t_end:
            sys.exit("convergence: %s did not stop at t_end = %g: %s" % (label, t_end, s))
        return r

    # --- orders ---------------------------------------------------------------------------
    t_end = p["t_end"]
    ref = trajectory("orders-reference", t_end, ["--integrator", "cvode-bdf", "--rtol",
                                                 REF["rtol"], "--atol", REF["atol"]])
    ref_pos = expkit.read_positions(ref)
    orders, order_fit = [], []
    for name, counts in p["steps"].items():
        for n in counts:
            dt = t_end / n
            r = trajectory("orders-%s-%d" % (name, n), t_end, ["--integrator", name, "--dt", dt])
            s = r.stats()
            orders.append(dict(integrator=name, steps=s["steps"], dt=dt,
                               error_m=expkit.max_position_error(expkit.read_positions(r),
                                                                 ref_pos),
                               cpu_seconds=s["cpu_seconds"]))
        rs = [o for o in orders if o["integrator"] == name]
        slope = expkit.loglog_slope([o["dt"] for o in rs], [o["error_m"] for o in rs])
        # the last halving alone, the closest to the asymptotic regime
        last = math.log(rs[-2]["error_m"] / rs[-1]["error_m"]) / math.log(2)
        order_fit.append(dict(integrator=name, expected=EXPECTED_ORDER[name], fitted=slope,
                              last_halving=last, dt_min=rs[-1]["dt"], dt_max=rs[0]["dt"]))
        print("orders: %-15s fitted %.3f (last halving %.3f), expected %d" % (
            name, slope, last, EXPECTED_ORDER[name]), flush=True)
        if not abs(slope - EXPECTED_ORDER[name]) <= ORDER_TOLERANCE:
            failures.append("%s: observed order %.3f, expected %d" % (
                name, slope, EXPECTED_ORDER[name]))
    expkit.write_csv(os.path.join(out, "orders.csv"), orders)
    expkit.write_csv(os.path.join(out, "orders_fit.csv"), order_fit)

    # --- tolerance --------------------------------------------------------------------------
    t_tol, ref_tol_pos = t_end, ref_pos
    listing = subprocess.run([expkit.knitsim_path(), "list", "integrators"], capture_output=True,
                             text=True, check=True).stdout.splitlines()[1:]
    adaptive = [f[0] for f in (line.split() for line in listing) if f and f[2] == "yes"]
    # static is an equilibrium accelerator (relaxation + Newton polish), not a trajectory method
    names = [n for n in (p["tol_integrators"] or adaptive) if n != "static"]
    tol_rows, tol_fit = [], []
    for name in names:
        for rtol in p["rtols"]:
            r = trajectory("tol-%s-%g" % (name, rtol), t_tol, [
                "--integrator", name, "--rtol", rtol, "--atol", 1e-3 * rtol])
            s = r.stats()
            tol_rows.append(dict(integrator=name, rtol=rtol, atol=1e-3 * rtol,
                                 error_m=expkit.max_position_error(expkit.read_positions(r),
                                                                   ref_tol_pos),
                                 steps=s["steps"], rhs_evals=s["rhs_evals"],
                                 lin_setups=s["lin_setups"], cpu_seconds=s["cpu_seconds"]))
        rs = [t for t in tol_rows if t["integrator"] == name]
        slope = expkit.loglog_slope([t["rtol"] for t in rs], [t["error_m"] for t in rs])
        tol_fit.append(dict(integrator=name, slope=slope,
                            error_at_rtol_1e_6=next((t["error_m"] for t in rs
                                                     if t["rtol"] == 1e-6), math.nan)))
        print("tolerance: %-15s error ~ rtol^%.3f" % (name, slope), flush=True)
    expkit.write_csv(os.path.join(out, "tolerance.csv"), tol_rows)
    expkit.write_csv(os.path.join(out, "tolerance_fit.csv"), tol_fit)
    if not all(t["slope"] > 0.5 for t in tol_fit if t["integrator"] == "cvode-bdf"):
        failures.append("cvode-bdf's error does not fall with rtol: %s" % tol_fit)

    # --- mesh -------------------------------------------------------------------------------
    mesh = []
    for n in p["mesh_n"]:
        l0 = W / n
        c = C_DEFAULT * (l0 / L0_DEFAULT) ** 2
        r = expkit.run_knitsim(out, "mesh-%d" % n, [
            "drape", "--scene", SCENE, "--set", "model.natural_length=%r" % l0,
            "--set", "model.damping=%r" % c])
        s = r.summary
        row = dict(n=n, natural_length_m=l0, damping=c, particles=s["grid"]["particles"],
                   status=s["status"], steps=s["steps"], cpu_seconds=s["cpu_seconds"],
                   t_final=s["t_final"], centre_sag_m=s["centre_sag_m"])
        for edge, coeffs in sorted(s["edge_coefficients"].items()):
            if edge == "top":  # the four edges of four_corner are equal by symmetry
                row.update({"top_p%d" % i: v for i, v in enumerate(coeffs)})
        mesh.append(row)
        print("mesh: n %-3d L0 %.4f m  %-11s sag %.6f m  cpu %.3g s" % (
            n, l0, s["status"], s["centre_sag_m"], s["cpu_seconds"]), flush=True)
    finest = mesh[-1]
    for row in mesh:
        row["sag_diff_to_finest_m"] = abs(row["centre_sag_m"] - finest["centre_sag_m"])
        row["coeff_diff_to_finest_pct"] = 100 * math.sqrt(sum(
            (row["top_p%d" % i] - finest["top_p%d" % i]) ** 2 for i in range(5)) / 5)
    expkit.write_csv(os.path.join(out, "mesh.csv"), mesh)
    if not all(m["status"] == "equilibrium" for m in mesh):
        failures.append("a mesh-refinement drape did not reach equilibrium")

    # --- ICA ----------------------------------------------------------------------------------
    ica = []
    table = re.compile(r"^\s*(\d+)\s+(\S+)\s+(\S+)\s+(\d+)\s+(\d+)\s*$")
    for problem in p["ica_problems"]:
        for seed in p["ica_seeds"]:
            text = subprocess.run([expkit.knitsim_path(), "optimize", "--problem", problem,
                                   "--dim", "10", "--seed", str(seed)], capture_output=True,
                                  text=True, check=True).stdout
            for line in text.splitlines():
                m = table.match(line)
                if m:
                    ica.append(dict(problem=problem, dim=10, seed=seed, decade=int(m.group(1)),
                                    evaluations=int(m.group(5)), best=float(m.group(2)),
                                    mean=float(m.group(3))))
    if p["fit_seeds"]:
        twin = expkit.run_knitsim(out, "fit-twin", ["drape", "--scene", SCENE])
        target = os.path.join(out, "fit-twin-target.csv")
        expkit.write_target_from(twin, target)
        for seed in p["fit_seeds"]:
            r = expkit.run_knitsim(out, "fit-%d" % seed, [
                "fit", "--scene", SCENE, "--target", target, "--seed", seed,
                "--decades", 10, "--countries", 15])
            for h in csv.DictReader(open(os.path.join(r.folder, "history.csv"))):
                ica.append(dict(problem="fit_four_corner", dim=5, seed=seed,
                                decade=int(h["decade"]), evaluations=int(h["evaluations"]),
                                best=float(h["best"]), mean=float(h["mean"])))
    expkit.write_csv(os.path.join(out, "ica.csv"), ica)
    for problem in dict.fromkeys(r["problem"] for r in ica):
        finals = [r["best"] for r in ica if r["problem"] == problem
                  and r["decade"] == max(x["decade"] for x in ica
                                         if x["problem"] == problem and x["seed"] == r["seed"])]
        print("ica: %-16s final best over %d seeds: min %.4g median %.4g max %.4g" % (
            problem, len(finals), min(finals), sorted(finals)[len(finals) // 2], max(finals)))
        for seed in dict.fromkeys(r["seed"] for r in ica if r["problem"] == problem):
            bests = [r["best"] for r in ica if r["problem"] == problem and r["seed"] == seed]
            if any(b > a for a, b in zip(bests, bests[1:])):
                failures.append("ICA best cost rose between decades (%s, seed %d)" % (
                    problem, seed))

    expkit.write_manifest(args, "convergence", ref, {
        "scene": SCENE, "reference": dict(integrator="cvode-bdf", **REF),
        "plan": {k: v for k, v in p.items()}, "order_tolerance": ORDER_TOLERANCE,
        "mesh_damping": "c = 12 N s/m x (L0 / 0.049 m)^2 (constant c/m)"})
    expkit.finish(args)
    for f in failures:
        print("convergence: CHECK FAILED: " + f, file=sys.stderr)
    print("convergence: wrote %s/{orders,orders_fit,tolerance,tolerance_fit,mesh,ica}.csv" % out)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
