"""Work-precision study: every integrator on the four_corner and two_corner
drapes and the single_tuck knit chart, without and with yarn contact (knit_contact), over a
sweep of rtol (adaptive methods) or dt (fixed-step methods). Error of the equilibrium positions
(max over particles; knit_contact ranks on that of the shape, blind to in-plane rigid motion)
and of the Eq. 5 edge coefficients against a tight reference, against CPU time, RHS
evaluations and linear-solver set-ups. Called by run.sh; see README.md. `--scenes` runs some
scenes and keeps the other scenes' rows of OUT.

Outputs in --out: runs.csv (one row per run, including the extrapolated and skipped ones),
references.csv, best.csv (cheapest integrator per accuracy level), manifest.json. CPU:
cpu_seconds is the integrator's, the run's (run_cpu_seconds) less, for the knit, the yarn
clearance measuring `knitsim knit` does inside the run (clearance_states measurements taking
clearance_cpu_seconds), as in experiments/transient: the integrators are compared on their work.
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

CHART = os.path.join(expkit.ROOT, "models", "charts", "single_tuck.chart")
# Reference: cvode-bdf at rtol 1e-10 (atol 1e-13 on the drapes; the knit runs keep the knit
# CLI's default atol 1e-9: this driver passes no --atol to knit)
# with equilibrium_tol 1e-9: the static residual has a round-off floor of ~2.5e-10 on
# four_corner (rtol 1e-10 and static both stall there), so 1e-9 is the tightest reachable stop.
REF_RTOL, REF_ATOL, REF_EQ_TOL = 1e-10, 1e-13, 1e-9
ATOL_PER_RTOL = 1e-3   # sweep: atol = 1e-3 rtol (m, m/s): the default pair 1e-6 / 1e-9
ERROR_LEVELS = [1e-3, 1e-5, 1e-7, 1e-9]  # m, accuracy levels of best.csv
# The equilibrium solver integrates no transient on these scenes (no pin moves): its accuracy
# knob is the stop, run.position_tol (m, the Newton correction), not rtol.
POSITION_TOLS = [1e-4, 1e-6, 1e-8, 1e-10]


# knit: the stabilised network without contact; knit_contact: the same chart with the
# yarn-contact barrier at its default stiffness (docs/knit.md "Yarn contact"), both named.
NO_CONTACT = ["--set", "knit.contact=0"]
CONTACT = ["--set", "knit.contact=10"]


def scene_args(scene):
    if scene == "knit":
        return ["knit", "--chart", CHART] + NO_CONTACT
    if scene == "knit_contact":
        return ["knit", "--chart", CHART] + CONTACT
    return ["drape", "--scene", scene]


def contact_columns(summary):
    """runs.csv's yarn columns of a knit run (empty for a drape): the centrelines' clearance
    (min over the run, at the end; in r), designed crossings changed, and with contact the
    pairs in contact and the cut renewals at the end."""
    yarn = (summary or {}).get("yarn") or {}
    contact = (summary or {}).get("contact") or {}
    return dict(clearance_min_r=yarn.get("clearance_min_over_r", ""),
                clearance_end_r=yarn.get("clearance_end_over_r", ""),
                crossings_changed=yarn.get("crossings_changed", ""),
                pairs_in_contact=contact.get("pairs_in_contact", ""),
                renewals_cut=contact.get("renewals_cut", ""))


def shape_error(a, b):
    """(max over particles of |R x_a + c - x_b|, R's angle in degrees) after the least-squares
    in-plane rotation R (about z) and translation c: the error of the shape, blind to the
    in-plane rigid motions that cost an unpinned chart no energy; inf as max_position_error."""
    if set(a) != set(b) or not a:
        return math.inf, math.nan
    n = len(a)
    ca = [sum(p[j] for p in a.values()) / n for j in range(3)]
    cb = [sum(p[j] for p in b.values()) / n for j in range(3)]
    sdot = scross = 0.0
    for k, pa in a.items():
        ax, ay = pa[0] - ca[0], pa[1] - ca[1]
        bx, by = b[k][0] - cb[0], b[k][1] - cb[1]
        sdot += ax * bx + ay * by
        scross += ax * by - ay * bx
    th = math.atan2(scross, sdot)
    c, s = math.cos(th), math.sin(th)
    err = 0.0
    for k, pa in a.items():
        ax, ay, az = (pa[j] - ca[j] for j in range(3))
        d = math.sqrt((c * ax - s * ay - (b[k][0] - cb[0])) ** 2 +
                      (s * ax + c * ay - (b[k][1] - cb[1])) ** 2 + (az - (b[k][2] - cb[2])) ** 2)
        if not math.isfinite(d):
            return math.inf, math.nan
        err = max(err, d)
    return err, math.degrees(th)


# knit_contact's reference: implicit-euler at REF_CONTACT_DT (README "knit_contact").
REF_CONTACT_DT = 0.05


def sweeps(quick):
    """Per scene: reference run, the rtols, the adaptive integrators to run (None: every one but
    those in `skip`), and the fixed-step plans {integrator: [dt] or ('factor', [f]) = f x the
    predicted stability limit, or 'extrapolate'}."""
    rtols = [1e-4, 1e-7] if quick else [10.0 ** -e for e in range(3, 11)]
    if quick:
        return {
            "four_corner": dict(rtols=rtols, integrators=["cvode-bdf", "equilibrium"],
                                fixed={"implicit-euler": [100.0, 10.0],
                                       "euler": "extrapolate"}),
            "knit": dict(rtols=rtols, integrators=["cvode-bdf"],
                         fixed={"implicit-euler": [1e-4, 1e-5],
                                "verlet": ("factor", [0.5, 0.125]),
                                "euler": ("factor", [0.5, 0.125])}),
            "knit_contact": contact_plan(rtols, ["cvode-bdf"], {"implicit-euler": [1.0, 0.1]}),
        }
    return {
        "four_corner": dict(rtols=rtols, integrators=None,
                            fixed={"implicit-euler": [300.0, 100.0, 30.0, 10.0, 1.0],
                                   "verlet": ("factor", [0.9, 0.5]),
                                   "euler": "extrapolate"}),
        "two_corner": dict(rtols=rtols, integrators=None,
                           fixed={"implicit-euler": [3000.0, 1000.0, 300.0, 100.0],
                                  "verlet": "extrapolate", "euler": "extrapolate"}),
        # The knit chart is paper 2's bare network, a mechanism: its rest state depends on the
        # path (docs/knit.md), so the equilibrium solver, which takes none, is not compared.
        "knit": dict(rtols=rtols, integrators=None, skip=["equilibrium"],
                     fixed={"implicit-euler": [1e-3, 1e-4, 1e-5, 1e-6],
                            "verlet": ("factor", [0.9, 0.5, 0.25, 0.125, 0.0625, 0.03125]),
                            "euler": ("factor", [0.9, 0.5, 0.25, 0.125, 0.0625, 0.03125])}),
        "knit_contact": contact_plan(
            [10.0 ** -e for e in range(1, 11)], None,
            {"implicit-euler": [1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 1e-3],
             "verlet": ("factor", [0.9, 0.5, 0.125, 0.03125]),
             "euler": ("factor", [0.9, 0.5, 0.125, 0.03125])}),
    }


def contact_plan(rtols, integrators, fixed):
    """knit_contact: the knit chart with yarn contact. Every integrator, the equilibrium solver
    too (over rtol: knit has no run.position_tol); rtol from 0.1 (the loose extremes). Its reference is implicit-euler
    (cvode-bdf crawls there), its errors are of the shape (the chart spins in-plane, README),
    and every sweep (dt and position_tol too) stops at its first wall-capped run: the contact
    runs that do not settle hit the cap, and the full run is to stay ~15 min."""
    return dict(rtols=rtols, integrators=integrators, error="shape_err_m", skip_after_cap=True,
                reference=dict(integrator="implicit-euler", dt=REF_CONTACT_DT, rtol=0.0,
                               atol=0.0),
                fixed=fixed)


def catalog():
    """[(name, adaptive, explicit)] from `knitsim list integrators`."""
    import subprocess
    out = subprocess.run([expkit.knitsim_path(), "list", "integrators"], capture_output=True,
                         text=True, check=True).stdout.splitlines()[1:]
    return [(f[0], f[2] == "yes", f[3] == "yes") for f in (line.split() for line in out) if f]


def main():
    def extra(p):
        p.add_argument("--wall-cap", type=float, default=None,
                       help="wall-clock cap per run, s (default 20, quick 5); an integrator's "
                            "tighter tolerances are skipped once one run hits it")
        p.add_argument("--scenes", default=None,
                       help="comma-separated scenes to run (default: all); the rows of the "
                            "other scenes are kept from OUT's runs.csv, references.csv and "
                            "manifest.json")
    args = expkit.parse_args("work_precision", "work_precision", extra)
    wall_cap = args.wall_cap or (5.0 if args.quick else 20.0)
    explicit_cap = 5000 if args.quick else 50000   # steps of a capped (extrapolated) run
    cat = catalog()
    all_plans = sweeps(args.quick)
    chosen = args.scenes.split(",") if args.scenes else list(all_plans)
    unknown = [s for s in chosen if s not in all_plans]
    if unknown:
        sys.exit("work_precision: unknown scene(s) %s; known: %s" % (unknown, list(all_plans)))
    plans = {k: v for k, v in all_plans.items() if k in chosen}
    rows, refs = [], []
    sample = None

    for scene, plan in plans.items():
        is_knit = scene.startswith("knit")
        base = scene_args(scene)

        def run(label, integ, extra_args):
            opts = ["--integrator", integ] + extra_args + ["--max-wall", wall_cap]
            if not is_knit:
                opts += ["--target", target]
            return expkit.run_knitsim(args.out, "%s-%s" % (scene, label), base + opts,
                                      timeout=wall_cap * 3 + 30)

        # Reference: cvode-bdf at REF_RTOL, or the plan's own (knit_contact, see sweeps)
        rp = plan.get("reference", dict(integrator="cvode-bdf", rtol=REF_RTOL, dt=0.0,
                                        atol=(1e-9 if is_knit else REF_ATOL)))
        ref_opts = ["--integrator", rp["integrator"],
                    "--set", "run.equilibrium_tol=%g" % REF_EQ_TOL]
        ref_opts += ["--dt", rp["dt"]] if rp["dt"] else ["--rtol", rp["rtol"]]
        if not is_knit:
            ref_opts += ["--atol", REF_ATOL]
        ref = expkit.run_knitsim(args.out, scene + "-reference", base + ref_opts, timeout=900)
        sample = sample or ref
        if ref.stats().get("status") != "equilibrium":
            sys.exit("work_precision: reference of %s did not reach equilibrium: %s"
                     % (scene, ref.stats().get("message")))
        ref_pos = expkit.read_positions(ref)
        target = os.path.join(args.out, scene + "-reference-target.csv")
        if not is_knit:
            expkit.write_target_from(ref, target)
        refs.append(dict(scene=scene, integrator=rp["integrator"], rtol=rp["rtol"],
                         atol=rp["atol"], dt=rp["dt"], equilibrium_tol=REF_EQ_TOL,
                         status=ref.stats()["status"], residual=ref.stats()["residual"],
                         newton_step_m=ref.stats().get("newton_step", math.nan),
                         newton_floor_m=ref.stats().get("newton_floor", math.nan),
                         t_final=ref.stats()["t_final"],
                         steps=ref.stats()["steps"],
                         cpu_seconds=expkit.integrator_cpu(ref.summary),
                         run_cpu_seconds=ref.stats()["cpu_seconds"],
                         **contact_columns(ref.summary)))

        def record(r, integ, rtol, atol, dt, measured="yes"):
            s = r.stats() if r.summary else {}
            row = dict(scene=scene, integrator=integ, rtol=rtol, atol=atol, dt=dt,
                       position_tol=math.nan, status=s.get("status", "timeout"),
                       measured=measured,
                       t_final=s.get("t_final", math.nan), steps=s.get("steps", 0),
                       rhs_evals=s.get("rhs_evals", 0), jac_evals=s.get("jac_evals", 0),
                       lin_setups=s.get("lin_setups", 0),
                       # the integrator's CPU: the run's (run_cpu_seconds) less, for the knit,
                       # the yarn clearance measuring inside the run (clearance_cpu_seconds)
                       cpu_seconds=expkit.integrator_cpu(r.summary),
                       run_cpu_seconds=s.get("cpu_seconds", math.nan),
                       **expkit.clearance_columns(r.summary),
                       **contact_columns(r.summary),
                       residual=s.get("residual", math.nan),
                       newton_step_m=s.get("newton_step", math.nan),
                       newton_floor_m=s.get("newton_floor", math.nan), pos_err_m=math.nan,
                       shape_err_m=math.nan, rotation_deg=math.nan, coeff_err_pct=math.nan,
                       objective_pct=math.nan, cpu_per_step=math.nan, rhs_per_step=math.nan)
            if measured == "yes" and r.summary:
                row["dt"] = s.get("dt", dt) or dt
                pos = expkit.read_positions(r)
                row["pos_err_m"] = expkit.max_position_error(pos, ref_pos)
                if is_knit:
                    row["shape_err_m"], row["rotation_deg"] = shape_error(pos, ref_pos)
                if not is_knit and "edge_coefficients" in r.summary:
                    row["coeff_err_pct"] = expkit.coefficient_error(
                        r.summary["edge_coefficients"], ref.summary["edge_coefficients"])
                    row["objective_pct"] = r.summary["objective"]
            if measured.startswith("skipped"):
                row["status"] = "skipped"
            rows.append(row)
            print("%-12s %-16s rtol %-8.0e dt %-9.3g %-12s cpu %-9.3g err %.3g m shape %.3g m"
                  % (scene, integ, rtol, row["dt"], row["status"], row["cpu_seconds"],
                row["pos_err_m"], row["shape_err_m"]), flush=True)
            return row

        # Adaptive methods over rtol; explicit ones on the drapes are stability-bound (~1e8
        # steps): one capped run each, extrapolated below.
        names = plan["integrators"] or [n for n, a, _ in cat
                                        if a and n not in plan.get("skip", [])]
        to_extrapolate = []
        for name, adaptive, explicit in cat:
            if not adaptive or name not in names:
                continue
            if explicit and not is_knit:
                to_extrapolate.append(name)
                continue
            # `knitsim knit` has no run.position_tol: there the solver's knob is the rtol of its
            # cvode-bdf phases, swept below like the other adaptive methods.
            if name == "equilibrium" and not is_knit:
                capped = False
                for tol in (POSITION_TOLS[1:2] if args.quick else POSITION_TOLS):
                    if capped:
                        row = record(expkit.Run("", None, None, ""), name, 0.0, 0.0, 0.0,
                                     measured="skipped: a looser position_tol hit the wall cap")
                    else:
                        row = record(run("%s-ptol%g" % (name, tol), name,
                                         ["--set", "run.position_tol=%g" % tol]),
                                     name, 0.0, 0.0, 0.0)
                        capped = (plan.get("skip_after_cap") and
                                  row["status"] in ("wall_limit", "timeout"))
                    row["position_tol"] = tol
                continue
            capped = False
            for rtol in plan["rtols"]:
                atol = ATOL_PER_RTOL * rtol
                if capped:
                    record(expkit.Run("", None, None, ""), name, rtol, atol, 0.0,
                           measured="skipped: a looser rtol hit the wall cap")
                    continue
                opts = ["--rtol", rtol] + ([] if is_knit else ["--atol", atol])
                row = record(run("%s-rtol%g" % (name, rtol), name, opts), name, rtol,
                             atol if not is_knit else 1e-9, 0.0)
                capped = row["status"] in ("wall_limit", "timeout")

        # Fixed-step methods over dt.
        for name, plan_dt in plan["fixed"].items():
            if plan_dt == "extrapolate":
                to_extrapolate.append(name)
                continue
            if isinstance(plan_dt, tuple):
                probe = run(name + "-probe", name, ["--set", "run.t_max=1e-9"])
                dt_pred = probe.stats()["dt_predicted"]
                dts = [f * dt_pred for f in plan_dt[1]]
            else:
                dts = plan_dt
            capped = False
            for dt in dts:
                if capped:
                    record(expkit.Run("", None, None, ""), name, 0.0, 0.0, dt,
                           measured="skipped: a larger dt hit the wall cap")
                    continue
                row = record(run("%s-dt%g" % (name, dt), name, ["--dt", dt]), name, 0.0, 0.0, dt)
                capped = plan.get("skip_after_cap") and row["status"] in ("wall_limit", "timeout")

        # Extrapolated costs: time per step and mean step from a capped run, times the earliest
        # physical time at which any measured run of this scene met the equilibrium criterion
        # (static and equilibrium are left out: a Newton polish ends static's relaxation early,
        # and the equilibrium solver integrates no time, t_final 0). two_corner's early
        # states (a nearly flat sheet) cannot be measured (its side edges have no depth yet,
        # knitsim exits 2), so its explicit methods take the time per step and the step of
        # four_corner's run of the same method: same grid, masses and springs,
        # and the same light edge particles set the stability limit.
        settled = [r["t_final"] for r in rows if r["scene"] == scene
                   and r["status"] == "equilibrium"
                   and r["integrator"] not in ("static", "equilibrium")]
        t_settle = min(settled + [ref.stats()["t_final"]])
        for name in to_extrapolate:
            if scene == "two_corner":
                donors = [r for r in rows if r["scene"] == "four_corner" and r["integrator"] == name
                          and r["steps"] > 0 and r["status"] not in ("diverged", "skipped")]
                if not donors:
                    continue
                d = max(donors, key=lambda r: r["dt"])
                measured_donor = not math.isfinite(d["cpu_per_step"])
                cpu_step = d["cpu_seconds"] / d["steps"] if measured_donor else d["cpu_per_step"]
                rhs_step = d["rhs_evals"] / d["steps"] if measured_donor else d["rhs_per_step"]
                mean_h = d["dt"]
                how = ("extrapolated: time per step and step of four_corner, t_settle %.4g s"
                       % t_settle)
                row = record(expkit.Run("", None, None, ""), name, 0.0, 0.0, mean_h, measured=how)
            else:
                r = run(name + "-capped", name, ["--max-steps", explicit_cap])
                s = r.stats()
                mean_h = s["t_final"] / s["steps"]
                cpu_step = expkit.integrator_cpu(r.summary) / s["steps"]
                rhs_step = s["rhs_evals"] / s["steps"]
                row = record(r, name, 0.0, 0.0, s["dt"] or mean_h,
                             measured="extrapolated: %d steps timed, t_settle %.4g s" % (
                                 s["steps"], t_settle))
            steps = t_settle / mean_h
            row.update(status="extrapolated", t_final=t_settle, steps=steps,
                       rhs_evals=rhs_step * steps, cpu_seconds=cpu_step * steps,
                       run_cpu_seconds=cpu_step * steps,  # drapes: no clearance measuring
                       cpu_per_step=cpu_step, rhs_per_step=rhs_step, dt=mean_h)

    # With --scenes, the other scenes' rows (and manifest) of an earlier run in OUT are kept.
    old_manifest = expkit.read_json(args.out, "manifest.json") if args.scenes else {}

    def merged(name, new, fields):
        if not args.scenes:
            return new, fields
        old = expkit.read_rows(args.out, name)
        fields = fields + [f for f in (old[0].keys() if old else []) if f not in fields]
        order = list(dict.fromkeys([r["scene"] for r in old] + list(plans)))
        return [r for sc in order for r in (new if sc in plans else old)
                if r["scene"] == sc], fields

    expkit.write_csv(os.path.join(args.out, "runs.csv"),
                     *merged("runs.csv", rows, list(rows[0].keys())))
    expkit.write_csv(os.path.join(args.out, "references.csv"),
                     *merged("references.csv", refs, list(refs[0].keys())))

    # Cheapest measured run per scene and accuracy level (equilibrium reached, error <= level).
    # knit_contact ranks on the shape error (error_measure), the others on the position error.
    best = []
    for scene in plans:
        err = plans[scene].get("error", "pos_err_m")
        for level in ERROR_LEVELS:
            ok = sorted((r for r in rows if r["scene"] == scene and r["status"] == "equilibrium"
                         and r[err] <= level), key=lambda r: r["cpu_seconds"])
            per_integ = {}
            for r in ok:
                per_integ.setdefault(r["integrator"], r)
            ranked = list(per_integ.values())
            if not ranked:
                best.append(dict(scene=scene, error_level_m=level, best="none",
                                 error_measure=err))
                continue
            w = ranked[0]
            best.append(dict(scene=scene, error_level_m=level, best=w["integrator"],
                             rtol=w["rtol"], dt=w["dt"], position_tol=w["position_tol"],
                             cpu_seconds=w["cpu_seconds"],
                             pos_err_m=w["pos_err_m"], error_measure=err,
                             shape_err_m=w["shape_err_m"],
                             runner_up=ranked[1]["integrator"] if len(ranked) > 1 else "",
                             runner_up_cpu_ratio=(ranked[1]["cpu_seconds"] / w["cpu_seconds"]
                                                  if len(ranked) > 1 else math.nan)))
    expkit.write_csv(os.path.join(args.out, "best.csv"), *merged("best.csv", best, [
        "scene", "error_level_m", "best", "rtol", "dt", "position_tol", "cpu_seconds",
        "pos_err_m", "runner_up", "runner_up_cpu_ratio", "error_measure", "shape_err_m"]))
    plan_info = {k: {"rtols": v["rtols"], "fixed": {n: str(d) for n, d in v["fixed"].items()},
                     "reference": v.get("reference", "cvode-bdf at the reference rtol")}
                 for k, v in plans.items()}
    expkit.write_manifest(args, "work_precision", sample, {
        "reference": {"integrator": "cvode-bdf", "rtol": REF_RTOL, "atol": REF_ATOL,
                      "equilibrium_tol": REF_EQ_TOL},
        "atol_per_rtol": ATOL_PER_RTOL, "wall_cap_s": wall_cap,
        "equilibrium_position_tols": POSITION_TOLS[1:2] if args.quick else POSITION_TOLS,
        "explicit_capped_steps": explicit_cap, "chart": os.path.relpath(CHART, expkit.ROOT),
        "plans": plan_info})
    if old_manifest:
        # Keep the earlier run's provenance; this run's goes under scene_runs, per scene.
        new = expkit.read_json(args.out, "manifest.json")
        keep = ("command", "git_commit", "knitsim_build", "created_utc", "nproc",
                "load_average", "wall_cap_s")
        old_manifest.setdefault("plans", {}).update(plan_info)
        runs_of = old_manifest.setdefault("scene_runs", {})
        for scene in plans:
            runs_of[scene] = {k: new.get(k) for k in keep}
        with open(os.path.join(args.out, "manifest.json"), "w") as f:
            json.dump(old_manifest, f, indent=2)

    # Self-checks (the CI quick run fails on them): the knitsim objective against a target made
    # from the reference equals the coefficient error computed here, cvode-bdf at the tightest
    # swept rtol lands within 1e-6 m of the reference on every scene, and every equilibrium run
    # within twice the sum of the two states' own stops of it: each is within its Newton
    # correction of the true minimum, or within that correction's round-off floor where the
    # tolerance asks for less (two_corner: ~6e-9 m, above position_tol 1e-10).
    failures = []
    for r in rows:
        if not r["scene"].startswith("knit") and math.isfinite(r["objective_pct"]) and \
                abs(r["objective_pct"] - r["coeff_err_pct"]) > 1e-9 + 1e-6 * r["coeff_err_pct"]:
            failures.append("objective %.6g != coefficient error %.6g (%s %s)" % (
                r["objective_pct"], r["coeff_err_pct"], r["scene"], r["integrator"]))
    for scene, plan in plans.items():
        if scene == "knit_contact":
            continue   # cvode-bdf crawls there (docs/knit.md); checked below instead
        tight = [r for r in rows if r["scene"] == scene and r["integrator"] == "cvode-bdf"
                 and r["rtol"] == min(plan["rtols"])]
        if not tight or not tight[0]["pos_err_m"] <= 1e-6:
            failures.append("cvode-bdf at rtol %g on %s: error %s m > 1e-6 m" % (
                min(plan["rtols"]), scene, tight[0]["pos_err_m"] if tight else "missing"))
    ref_of = {r["scene"]: r for r in refs}
    for r in rows:
        # knit_contact: its Newton correction's floor is meaningless (no out-of-plane stiffness)
        if r["integrator"] != "equilibrium" or r["scene"] == "knit_contact":
            continue
        ref = ref_of[r["scene"]]
        bound = 2.0 * (max(r["position_tol"], r["newton_floor_m"]) +
                       max(ref["newton_step_m"], ref["newton_floor_m"]))
        if not r["pos_err_m"] <= bound:
            failures.append("equilibrium at position_tol %g on %s: error %s m > %g m" % (
                r["position_tol"], r["scene"], r["pos_err_m"], bound))
    # knit_contact: the reference keeps the yarns >= 0.9 r apart with no designed crossing
    # changed (docs/knit.md's target), and implicit-euler at dt 1 s (knit's default with
    # contact) settles within 1e-5 m (0.11 r) of the reference's shape.
    if "knit_contact" in plans:
        ref = ref_of["knit_contact"]
        if not (ref["clearance_min_r"] >= 0.9 and ref["crossings_changed"] == 0):
            failures.append("knit_contact reference: clearance %s r, %s crossings changed" % (
                ref["clearance_min_r"], ref["crossings_changed"]))
        ie1 = [r for r in rows if r["scene"] == "knit_contact"
               and r["integrator"] == "implicit-euler" and r["dt"] == 1.0]
        if not ie1 or ie1[0]["status"] != "equilibrium" or not ie1[0]["shape_err_m"] <= 1e-5:
            failures.append("knit_contact implicit-euler dt 1 s: %s, shape error %s m" % (
                (ie1[0]["status"], ie1[0]["shape_err_m"]) if ie1 else ("missing", "")))
    expkit.finish(args)
    for f in failures:
        print("work_precision: CHECK FAILED: " + f, file=sys.stderr)
    print("work_precision: wrote %s/{runs,references,best}.csv, manifest.json" % args.out)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
