#!/usr/bin/python3
"""Reductions study: what each "model only what the scene requires" reduction
saves against the full model, measured where the code allows it (README.md).

  state.csv     pinned particles are scene data, not state (models/spring_network.hpp): dof
                of each scene vs the 3 x all-particles count a pinned-in-the-state model would
                integrate.
  topology.csv  springs of the chosen topology only: springs, CPU per explicit-Euler step
                (fixed step count, the cost of one RHS) and a cvode-bdf drape, for a, b, c.
  stop.csv      stopping at equilibrium (docs/equilibrium.md) vs running to a fixed end time with the
                check disabled (run.equilibrium_tol = 1e-30): CPU, steps, and the max position
                difference from the equilibrium-stop state.
  static.csv    the `static` integrator (cvode-bdf relaxation + KINSOL Newton polish) vs
                cvode-bdf alone: CPU, steps, final residual, max position difference.
  symmetry.csv  four_corner solved on one quarter (model.symmetry = quarter: the two
                mid-plane mirrors) and on one eighth (= eighth: the diagonal mirror too), and
                two_corner on one half (= half: the mirror x = W/2; models/mirror_reduced.hpp)
                vs the full grid, per scene, grid size n and integrator:
                integrated dof, steps, RHS, set-ups, factorisations, CPU, speed-up, and the max
                position difference and Eq. 5 coefficient error of the unfolded equilibrium
                against the full one. The full and reduced runs alternate, so the medians
                see the same machine load.
  fits.csv      `knitsim fit` (ICA, the repro quick preset's budget: 10 countries, 6 decades,
                seed = sample) of the committed twin targets (paper_repro/data/targets) on the
                full grid and on the reduction the scene admits (four_corner: eighth;
                two_corner: half): objective, fitted parameters, evaluations, failed
                evaluations, CPU of the fit process; whether the reduced fit ends on the same
                country. Single runs (the fits alternate full / reduced).
Each section measures one reduction: its drapes run on the whole sheet (model.symmetry = none)
unless the row is a mirror reduction. CPU figures are medians of REPEATS runs of the solver's own
cpu_seconds (set-up and output excluded).
"""
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402


TARGETS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(
    __file__)))), "paper_repro", "data", "targets")


def symmetric_fits(args, samples, scenes):
    """fits.csv rows: each twin sample fitted on the full grid and on the scene's reduction."""
    reduction = {"four_corner": "eighth", "two_corner": "half"}
    rows = []
    for sample in samples:
        target = os.path.join(TARGETS, "twin_sample%d.csv" % sample)
        for scene in scenes:
            fits = {}
            for model in ("none", reduction[scene]):
                c0 = expkit.cpu_children()
                run = expkit.run_knitsim(args.out, "fit-%s-%d-%s" % (scene, sample, model), [
                    "fit", "--scene", scene, "--set", "model.symmetry=" + model, "--target",
                    target, "--countries", 10, "--decades", 6, "--seed", sample])
                fits[model] = (run.summary, expkit.cpu_children() - c0)
            full, full_cpu = fits["none"]
            for model, (s, cpu) in fits.items():
                p = s["params"]
                rows.append(dict(
                    sample=sample, scene=scene, model="full" if model == "none" else model,
                    objective=s["objective"], stiffness=p["stiffness"], damping=p["damping"],
                    elongation_limit=p["elongation_limit"], natural_length=p["natural_length"],
                    topology=p["topology"], evaluations=s["evaluations"],
                    failed_evaluations=s["failed_evaluations"], cpu_seconds=cpu,
                    speedup=full_cpu / cpu,
                    same_country=s["best_country"] == full["best_country"],
                    objective_relative_difference=abs(s["objective"] - full["objective"]) /
                    full["objective"]))
                print("fit", {k: rows[-1][k] for k in rows[-1]}, flush=True)
    return rows


def main():
    args = expkit.parse_args("reductions", "reductions")
    repeats = 1 if args.quick else 3
    scenes = ["four_corner"] if args.quick else ["four_corner", "two_corner"]
    counter = [0]

    def drape(scene, integ, extra):
        # One reduction at a time: the whole sheet unless the row asks for a mirror reduction.
        extra = [str(e) for e in extra]
        if not any(e.startswith("model.symmetry=") for e in extra):
            extra += ["--set", "model.symmetry=none"]
        counter[0] += 1
        return expkit.run_knitsim(args.out, "r%d" % counter[0], ["drape", "--scene", scene,
                                  "--integrator", integ] + extra)

    def median_run(scene, integ, extra):
        runs = [drape(scene, integ, extra) for _ in range(repeats)]
        cpu = statistics.median(r.summary["cpu_seconds"] for r in runs)
        return runs[-1], cpu

    topo = []
    euler_steps = 20000 if args.quick else 100000
    for t in ("a", "b", "c"):
        eu, eu_cpu = median_run("four_corner", "euler", ["--set", "model.topology=" + t,
                                                         "--max-steps", euler_steps])
        bdf, bdf_cpu = median_run("four_corner", "cvode-bdf", ["--set", "model.topology=" + t])
        topo.append(dict(topology=t, springs=eu.summary["grid"]["springs"],
                         euler_us_per_step=1e6 * eu_cpu / eu.summary["steps"],
                         bdf_status=bdf.summary["status"], bdf_steps=bdf.summary["steps"],
                         bdf_t_final=bdf.summary["t_final"], bdf_cpu_seconds=bdf_cpu))
        print("topology %s: %d springs, euler %.3g us/step, cvode-bdf %s %d steps %.3g s CPU" % (
            t, topo[-1]["springs"], topo[-1]["euler_us_per_step"], bdf.summary["status"],
            bdf.summary["steps"], bdf_cpu), flush=True)
    expkit.write_csv(os.path.join(args.out, "topology.csv"), topo)

    state, stop, static = [], [], []
    for scene in scenes:
        eq, eq_cpu = median_run(scene, "cvode-bdf", [])
        g = eq.summary["grid"]
        state.append(dict(scene=scene, particles=g["particles"], pinned=g["pinned"],
                          dof_in_state=g["dof"], dof_if_pins_were_state=3 * g["particles"],
                          saved_fraction=1 - g["dof"] / (3 * g["particles"])))
        eq_x = expkit.read_positions(eq)
        stop.append(dict(scene=scene, stop="equilibrium", t_final=eq.summary["t_final"],
                         steps=eq.summary["steps"], residual=eq.summary["residual"],
                         cpu_seconds=eq_cpu, cpu_ratio=1.0, max_position_difference_m=0.0))
        t_eq = eq.summary["t_final"]
        ends = [10 * t_eq] if args.quick else [2 * t_eq, 10 * t_eq, 1e7]
        for t_end in ends:
            r, cpu = median_run(scene, "cvode-bdf", ["--set", "run.equilibrium_tol=1e-30",
                                                     "--set", "run.t_max=%r" % t_end])
            stop.append(dict(scene=scene, stop="fixed t_end = %.3g s" % t_end,
                             t_final=r.summary["t_final"], steps=r.summary["steps"],
                             residual=r.summary["residual"], cpu_seconds=cpu,
                             cpu_ratio=cpu / eq_cpu,
                             max_position_difference_m=expkit.max_position_error(
                                 expkit.read_positions(r), eq_x)))
        st, st_cpu = median_run(scene, "static", [])
        static.append(dict(scene=scene, integrator="cvode-bdf", status=eq.summary["status"],
                           t_final=t_eq, steps=eq.summary["steps"],
                           residual=eq.summary["residual"], cpu_seconds=eq_cpu,
                           cpu_ratio=1.0, max_position_difference_m=0.0,
                           message=eq.summary["message"]))
        static.append(dict(scene=scene, integrator="static", status=st.summary["status"],
                           t_final=st.summary["t_final"], steps=st.summary["steps"],
                           residual=st.summary["residual"], cpu_seconds=st_cpu,
                           cpu_ratio=st_cpu / eq_cpu,
                           max_position_difference_m=expkit.max_position_error(
                               expkit.read_positions(st), eq_x),
                           message=st.summary["message"]))
        for row in stop[-len(ends) - 1:] + static[-2:]:
            print(scene, {k: row[k] for k in row if k != "scene"}, flush=True)
    symmetry = []
    sym = lambda name: ["--set", "model.symmetry=" + name]  # noqa: E731
    # "full" is asked for (model.symmetry = none): the default, auto, runs the largest reduction.
    four = [("full", sym("none")), ("quarter", sym("quarter")), ("eighth", sym("eighth"))]
    # (scene, n, integrators, models); implicit-euler (a factorisation per step) at n = 10 only,
    # for run time; on two_corner it needs ~3e5 steps of dt = 1 s.
    cases = [("four_corner", 10, ["equilibrium", "cvode-bdf"] if args.quick
              else ["equilibrium", "cvode-bdf", "implicit-euler"], four)]
    if not args.quick:
        cases += [("four_corner", 50, ["equilibrium", "cvode-bdf"], four),
                  ("two_corner", 10, ["equilibrium", "cvode-bdf"],
                   [("full", sym("none")), ("half", sym("half"))])]
    for scene, n, integs, models in cases:
        size = ["--set", "model.natural_length=%r" % (0.5 / n)] if n != 10 else []
        for integ in integs:
            rounds = [[drape(scene, integ, size + extra) for _, extra in models]
                      for _ in range(repeats)]
            full_run = rounds[-1][0]
            full_cpu = statistics.median(p[0].summary["cpu_seconds"] for p in rounds)
            full_x = expkit.read_positions(full_run)
            for k, (model, _) in enumerate(models):
                r = rounds[-1][k]
                cpu = statistics.median(p[k].summary["cpu_seconds"] for p in rounds)
                symmetry.append(dict(
                    scene=scene, n=n, integrator=integ, model=model,
                    dof=r.summary["grid"]["integrated_dof"],
                    status=r.summary["status"], steps=r.summary["steps"],
                    rhs_evals=r.summary["rhs_evals"], lin_setups=r.summary["lin_setups"],
                    factorisations=r.summary["factorisations"],
                    cpu_seconds=cpu, speedup=full_cpu / cpu,
                    max_position_difference_m=expkit.max_position_error(
                        expkit.read_positions(r), full_x),
                    coefficient_error_percent=expkit.coefficient_error(
                        r.summary["edge_coefficients"], full_run.summary["edge_coefficients"])))
                print("symmetry", {k2: symmetry[-1][k2] for k2 in symmetry[-1]}, flush=True)
    expkit.write_csv(os.path.join(args.out, "symmetry.csv"), symmetry)
    fits = symmetric_fits(args, [1] if args.quick else list(range(1, 10)), scenes)
    expkit.write_csv(os.path.join(args.out, "fits.csv"), fits)
    expkit.write_csv(os.path.join(args.out, "state.csv"), state)
    expkit.write_csv(os.path.join(args.out, "stop.csv"), stop)
    expkit.write_csv(os.path.join(args.out, "static.csv"), static)
    expkit.write_manifest(args, "reductions", extra={"repeats": repeats, "scenes": scenes})
    expkit.finish(args)
    worst = max(r["max_position_difference_m"] for r in stop + static + symmetry)
    if worst > 1e-6:  # the study's own check: every reduction lands on the same equilibrium
        sys.exit("reductions: a reduced run ends %.3g m from the equilibrium-stop state" % worst)


if __name__ == "__main__":
    main()
