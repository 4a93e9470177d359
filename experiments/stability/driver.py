#!/usr/bin/python3
"""Stability study: measured stability limits of the explicit integrators on
the four_corner drape vs the linear analysis of solvers/integrator.hpp, a dt x stiffness stability map,
cvode-bdf at the parameter extremes, and what every integrator does without damping.

Every number comes from `knitsim drape` runs (no knitsim code is linked); the exact linear
limits come from linear_limits.py on the independent model of experiments/peer/drape_scipy.py.

  limits.csv   per case (k, c, rho_A, L0) and method: predict_stable_dt (knitsim's per-dof
               Gershgorin bound, summary.json dt_predicted), estimate_stable_dt (the same
               with omega^2 capped by Lanczos estimates of the fastest undamped and overdamped
               modes, summary.json dt_estimated), the exact linear limit (all
               eigenvalues of J at the flat start), and the measured limit:
               euler, verlet: bisection on --dt; a run of `steps` steps is unstable if it ends
                 diverged (runaway or non-finite) or with a static residual > 1e3 (stable
                 runs stay at O(1): the sheet barely moves in that time); the bracket is
                 narrowed to 0.5 %;
               arkode-erk (adaptive, no fixed-step mode in knitsim): the mean accepted step
                 between t = 500 and 5500 x the exact limit (the stiffness-bound step the
                 error controller settles at).
  map.csv      euler and verlet at a log grid of dt x stiffness to t = T_map: stable or not,
               and the max position error against cvode-bdf at rtol 1e-10.
  bdf.csv      cvode-bdf to equilibrium at the extremes, default order and --max-order 2.
  undamped.csv c = 0: every integrator, what it reaches.
"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "peer"))
import expkit  # noqa: E402
import drape_scipy  # noqa: E402
import linear_limits  # noqa: E402

BASE = dict(stiffness=852.0, damping=12.0, areal_density=41.65, natural_length=0.049)
UNSTABLE_RESIDUAL = 1e3


def cases(quick):
    """(group, overrides of BASE) in measurement order."""
    if quick:
        return [("stiffness", {"stiffness": 1e5})]
    out = [("base", {})]
    out += [("stiffness", {"stiffness": k}) for k in (500.0, 1e5)]
    out += [("damping", {"damping": c}) for c in (20.0, 2.0, 0.5, 0.0)]
    out += [("areal_density", {"areal_density": 58.26})]
    out += [("mesh", {"natural_length": 0.04})]
    out += [("extreme", {"stiffness": 1e5, "damping": 0.0, "areal_density": 27.6})]
    return out


def full_params(over):
    p = dict(BASE)
    p.update(over)
    return p


def sets(p):
    args = []
    for key in ("stiffness", "damping", "areal_density", "natural_length"):
        scene_key = ("fabric." if key == "areal_density" else "model.") + key
        args += ["--set", "%s=%r" % (scene_key, p[key])]
    return args


def label(p):
    return "k%g-c%g-rho%g-L%g" % (p["stiffness"], p["damping"], p["areal_density"],
                                  p["natural_length"])


class Study:
    def __init__(self, args):
        self.args = args
        self.count = 0
        self.blown_up_without_summary = 0

    def drape(self, p, integrator, extra):
        """One run; None when knitsim wrote no summary because the edge fit of a blown-up (but
        finite) state failed (knitsim exits 2: "fit_polynomial: ... fewer than 5 distinct
        abscissae"), which only happens to unstable runs."""
        self.count += 1
        try:
            return expkit.run_knitsim(self.args.out, "r%d" % (self.count % 4),
                                      ["drape", "--scene", "four_corner", "--integrator",
                                       integrator] + sets(p) + [str(a) for a in extra])
        except SystemExit as e:
            if "fit_polynomial" not in str(e):
                raise
            self.blown_up_without_summary += 1
            return None

    def predicted(self, p, method):
        """(predict_stable_dt, estimate_stable_dt) at the flat start, s."""
        s = self.drape(p, method, ["--dt", 1e-9, "--max-steps", 1]).summary
        return s["dt_predicted"], s["dt_estimated"]

    def unstable(self, p, method, dt, steps):
        run = self.drape(p, method, ["--dt", dt, "--max-steps", steps])
        if run is None:
            return True
        s, r = run.summary, run.summary["residual"]
        return s["status"] == "diverged" or not math.isfinite(r) or r > UNSTABLE_RESIDUAL

    def bisect(self, p, method, ref, steps):
        """(lo, hi): lo stable, hi unstable, hi/lo - 1 <= 0.5 %."""
        lo, hi = 0.97 * ref, 1.03 * ref
        while self.unstable(p, method, lo, steps):
            hi, lo = lo, lo / 1.1
        while not self.unstable(p, method, hi, steps):
            lo, hi = hi, hi * 1.1
        while hi / lo - 1.0 > 0.005:
            mid = 0.5 * (lo + hi)
            if self.unstable(p, method, mid, steps):
                hi = mid
            else:
                lo = mid
        return lo, hi

    def erk_mean_step(self, p, h_exact):
        t1, t2 = 500 * h_exact, 5500 * h_exact
        a = self.drape(p, "arkode-erk", ["--set", "run.t_max=%r" % t1]).summary
        b = self.drape(p, "arkode-erk", ["--set", "run.t_max=%r" % t2]).summary
        return (t2 - t1) / (b["steps"] - a["steps"]), b["err_test_fails"] - a["err_test_fails"]


def measure_limits(study, quick, path):
    """Measures every case; rewrites `path` (CSV) after each one."""
    steps = 20000 if quick else 30000
    rows = []
    for group, over in cases(quick):
        p = full_params(over)
        both = {m: study.predicted(p, m) for m in ("euler", "verlet")}
        pred = {m: v[0] for m, v in both.items()}
        est = {m: v[1] for m, v in both.items()}
        model = drape_scipy.Drape(layout="four_corner", **p)
        exact = linear_limits.limits(model, pred["verlet"])
        for method in ("euler", "verlet", "arkode-erk"):
            row = dict(group=group, case=label(p), **p, method=method,
                       predicted=pred.get(method, math.nan),
                       estimated=est.get(method, math.nan), exact=exact[method],
                       omega_max=exact["omega_max"], steps_per_run=steps)
            if method == "arkode-erk":
                row["measured"], row["err_test_fails"] = study.erk_mean_step(p, exact[method])
                row["measured_lo"] = row["measured_hi"] = math.nan
            elif exact[method] > 0:
                lo, hi = study.bisect(p, method, exact[method], steps)
                row.update(measured_lo=lo, measured_hi=hi, measured=0.5 * (lo + hi))
            else:  # undamped euler: no stable step (see undamped.csv)
                row.update(measured_lo=math.nan, measured_hi=math.nan, measured=0.0)
            row["measured_over_predicted"] = (row["measured"] / row["predicted"]
                                              if row["predicted"] > 0 else math.nan)
            row["measured_over_estimated"] = (row["measured"] / row["estimated"]
                                              if row["estimated"] > 0 else math.nan)
            row["measured_over_exact"] = (row["measured"] / row["exact"]
                                          if row["exact"] > 0 else math.nan)
            rows.append(row)
            print("%-13s %-34s %-10s predicted %.4g estimated %.4g exact %.4g measured %.4g"
                  " (x%.4f of predicted, x%.4f of estimated, x%.4f of exact)"
                  % (group, label(p), method, row["predicted"], row["estimated"], row["exact"],
                     row["measured"], row["measured_over_predicted"],
                     row["measured_over_estimated"], row["measured_over_exact"]), flush=True)
        expkit.write_csv(path, rows)
    return rows


def stability_map(study, quick):
    t_map = 0.01 if quick else 0.02
    ks = (852.0, 1e5) if quick else (500.0, 5000.0, 1e5)
    n_dt = 6 if quick else 9
    dts = [1e-6 * (300.0 ** (i / (n_dt - 1))) for i in range(n_dt)]  # 1e-6 .. 3e-4 s
    rows = []
    for k in ks:
        p = full_params({"stiffness": k})
        ref = study.drape(p, "cvode-bdf", ["--rtol", 1e-10, "--atol", 1e-14,
                                           "--set", "run.t_max=%r" % t_map])
        ref_x = expkit.read_positions(ref)
        for method in ("euler", "verlet"):
            for dt in dts:
                run = study.drape(p, method, ["--dt", dt, "--set", "run.t_max=%r" % t_map])
                s = run.summary if run else dict(status="diverged (no summary)", steps=-1,
                                                 residual=math.inf)
                stable = (s["status"] != "diverged" and math.isfinite(s["residual"])
                          and s["residual"] <= UNSTABLE_RESIDUAL)
                err = expkit.max_position_error(expkit.read_positions(run), ref_x) if stable else math.inf
                rows.append(dict(method=method, stiffness=k, dt=dt, t_end=t_map,
                                 status=s["status"], steps=s["steps"], residual=s["residual"],
                                 stable=int(stable), error_m=err,
                                 reference_t_final=ref.summary["t_final"]))
    return rows


def bdf_extremes(study, quick):
    points = [{}] + ([] if quick else
                     [{"stiffness": k, "damping": c, "areal_density": r}
                      for k in (500.0, 1e5) for c in (20.0, 1.0) for r in (27.6, 58.26)])
    rows = []
    for over in points:
        p = full_params(over)
        for order in (0, 2):
            s = study.drape(p, "cvode-bdf", ["--max-order", order, "--max-steps",
                                             20000 if quick else 100000, "--max-wall", 60]).summary
            rows.append(dict(case=label(p), **p, max_order_option=order, status=s["status"],
                             t_final=s["t_final"], steps=s["steps"], rhs_evals=s["rhs_evals"],
                             jac_evals=s["jac_evals"], lin_setups=s["lin_setups"],
                             nonlin_fails=s["nonlin_fails"], err_test_fails=s["err_test_fails"],
                             max_order_used=s["max_order_used"], residual=s["residual"],
                             cpu_seconds=s["cpu_seconds"]))
            print("cvode-bdf %s max-order %d: %s t %.4g steps %d fails (nl %d, err %d) order %d "
                  "cpu %.3g s" % (label(p), order, s["status"], s["t_final"], s["steps"],
                                  s["nonlin_fails"], s["err_test_fails"], s["max_order_used"],
                                  s["cpu_seconds"]), flush=True)
    return rows


def undamped(study, quick):
    p = full_params({"damping": 0.0})
    cap = 5000 if quick else 50000
    runs = [("euler", ["--dt", 1e-5, "--max-steps", 20 * cap]),
            ("verlet", ["--set", "run.t_max=%r" % (1.0 if quick else 10.0)]),
            ("arkode-erk", ["--set", "run.t_max=%r" % (0.1 if quick else 1.0)]),
            ("cvode-bdf", ["--max-steps", cap]),
            ("cvode-bdf", ["--max-steps", cap, "--max-order", 2]),
            ("implicit-euler", ["--max-steps", cap]),
            ("static", ["--max-steps", cap])]
    rows = []
    for integ, extra in runs:
        s = study.drape(p, integ, extra + ["--max-wall", 120]).summary
        rows.append(dict(integrator=integ, options=" ".join(str(e) for e in extra),
                         status=s["status"], t_final=s["t_final"], steps=s["steps"],
                         dt=s["dt"], residual=s["residual"], max_order_used=s["max_order_used"],
                         err_test_fails=s["err_test_fails"], nonlin_fails=s["nonlin_fails"],
                         cpu_seconds=s["cpu_seconds"], message=s["message"]))
        print("c = 0, %s %s: %s after %d steps, t %.4g s, residual %.3g" % (
            integ, rows[-1]["options"], s["status"], s["steps"], s["t_final"], s["residual"]),
            flush=True)
    return rows


# Spurious equilibria at the extremes: where each method ends, on the three
# built-in scenes' whole sheets, against the state the damped dynamics reach from rest
# (cvode-bdf at rtol 1e-8, atol 1e-11). Every run's end state is checked by knitsim (summary.json:
# status, certificate, energy against energy_reference); the driver adds the distance.
SPURIOUS_SCENES = ("four_corner", "two_corner", "two_corner_slack")
SAME_STATE_M = 1e-6  # within this of the reference: the same equilibrium


def spurious_plan(quick):
    """[(integrator, setting label, knitsim options)] of the map."""
    if quick:
        return [("implicit-euler", "dt 1e4", ["--dt", 1e4]),
                ("cvode-bdf", "rtol 1e-2", ["--rtol", 1e-2, "--atol", 1e-5])]
    plan = [("implicit-euler", "dt %g" % dt, ["--dt", dt]) for dt in (10.0, 100.0, 1e3, 1e4, 1e5)]
    for integ in ("cvode-bdf", "arkode-dirk", "arkode-imex", "cvode-bdf-gmres"):
        plan += [(integ, "rtol %g" % r, ["--rtol", r, "--atol", 1e-3 * r])
                 for r in (1e-1, 1e-2, 1e-3, 1e-4)]
    # The equilibrium solver's globalisation (first flow step 1 mm, trust-region factors,
    # 60 rejections before the fallback) is compiled in, not a scene key; what a user can
    # set is the tolerance of its cvode-bdf phases (the pins' move, a fallback) and the stop.
    plan += [("equilibrium", "rtol %g" % r, ["--rtol", r, "--atol", 1e-3 * r])
             for r in (1e-1, 1e-2, 1e-3, 1e-6)]
    plan += [("equilibrium", "position_tol %g" % t, ["--set", "run.position_tol=%g" % t])
             for t in (1e-6, 1e-3)]
    return plan


def spurious(args, quick):
    rows = []
    n = 0
    for scene in ((SPURIOUS_SCENES[1],) if quick else SPURIOUS_SCENES):
        base = ["drape", "--scene", scene, "--no-pictures", "--max-wall", 60 if quick else 120]
        ref = expkit.run_knitsim(args.out, "spurious-ref", base + [
            "--integrator", "cvode-bdf", "--rtol", 1e-8, "--atol", 1e-11])
        if ref.summary["status"] != "equilibrium":
            sys.exit("stability: the reference of %s did not settle" % scene)
        ref_x = expkit.read_positions(ref)
        for integ, setting, extra in [("cvode-bdf", "reference", [])] + spurious_plan(quick):
            n += 1
            r = ref if setting == "reference" else expkit.run_knitsim(
                args.out, "spurious-%d" % (n % 4), base + ["--integrator", integ] + extra)
            s = r.summary or {}
            dist = expkit.max_position_error(expkit.read_positions(r), ref_x) if s else math.nan
            status, cert = s.get("status", "no_summary"), s.get("certificate", "")
            if status == "equilibrium":
                outcome = "same equilibrium" if dist <= SAME_STATE_M else "another minimum"
            elif status == "spurious_equilibrium":
                outcome = "spurious (energy above the reference)"
            elif cert == "not_minimum":
                outcome = "saddle"
            else:
                outcome = "no equilibrium (%s)" % status
            rows.append(dict(scene=scene, integrator=integ, setting=setting,
                             options=" ".join(str(e) for e in extra), status=status,
                             certificate=cert, outcome=outcome, distance_m=dist,
                             energy=s.get("energy", math.nan),
                             energy_reference=s.get("energy_reference", math.nan),
                             reference_energy=ref.summary["energy"],
                             t_final=s.get("t_final", math.nan), steps=s.get("steps", 0),
                             min_eigenvalue=s.get("min_eigenvalue", math.nan),
                             saddle_escapes=s.get("saddle_escapes", 0),
                             fallbacks=s.get("fallbacks", 0),
                             cpu_seconds=s.get("cpu_seconds", math.nan)))
            print("%s %s %s: %s, %s, %.3g m, E %.4g J (ref. %.4g J)" % (
                scene, integ, setting, status, outcome, dist, rows[-1]["energy"],
                rows[-1]["energy_reference"]), flush=True)
    return rows


def main():
    args = expkit.parse_args("stability", "stability")
    study = Study(args)
    limits = measure_limits(study, args.quick, os.path.join(args.out, "limits.csv"))
    expkit.write_csv(os.path.join(args.out, "undamped.csv"), undamped(study, args.quick))
    expkit.write_csv(os.path.join(args.out, "bdf.csv"), bdf_extremes(study, args.quick))
    expkit.write_csv(os.path.join(args.out, "map.csv"), stability_map(study, args.quick))
    expkit.write_csv(os.path.join(args.out, "spurious.csv"), spurious(args, args.quick))
    explicit = [r for r in limits if r["method"] in ("euler", "verlet") and r["exact"] > 0]
    worst_pred = max(explicit, key=lambda r: abs(r["measured_over_predicted"] - 1))
    worst_est = max(explicit, key=lambda r: abs(r["measured_over_estimated"] - 1))
    worst_exact = max(explicit, key=lambda r: abs(r["measured_over_exact"] - 1))
    print("worst measured/predicted: %.4f (%s %s); worst measured/estimated: %.4f (%s %s); "
          "worst measured/exact: %.4f (%s %s)" % (
              worst_pred["measured_over_predicted"], worst_pred["method"], worst_pred["case"],
              worst_est["measured_over_estimated"], worst_est["method"], worst_est["case"],
              worst_exact["measured_over_exact"], worst_exact["method"], worst_exact["case"]))
    expkit.write_manifest(args, "stability", extra={"base": BASE, "runs": study.count,
                                                    "blown_up_without_summary":
                                                    study.blown_up_without_summary,
                                                    "unstable_residual": UNSTABLE_RESIDUAL})
    expkit.finish(args)
    if abs(worst_exact["measured_over_exact"] - 1) > 0.05:  # the study's own check
        sys.exit("stability: a measured limit is %.4f x the exact linear one (> 5 %% off)"
                 % worst_exact["measured_over_exact"])


if __name__ == "__main__":
    main()
