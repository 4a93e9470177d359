"""Transient work-precision: the states of two transients at fixed times
against a tight reference, for every integrator over its tolerances or steps; error against CPU
time. Called by run.sh; see README.md. Two cases (--only picks one):

  two_corner_slack  the drape (`knitsim drape`): the pins' 100 s move, then the fold;
  single_tuck       the knit tuck's ringing (`knitsim knit --chart models/charts/single_tuck.chart`,
                    the stabilised network without contact): the tuck pulls its loops in ~25 us, the
                    fabric rings (periods of tens of us) and settles over ~1 ms.

A state at time T is the end state of a run with `--set run.t_max=T` (every integrator stops
exactly at t_max: the SUNDIALS methods through their stop time, the fixed-step methods with a
shortened last step; the driver checks t_final), so each (integrator, setting, T) is one knitsim
run and its CPU is the cost of reaching T. The drape is the whole sheet (model.symmetry = none;
expkit.run_knitsim).

Outputs in --out: runs.csv (one row per run: case, integrator, rtol / atol / velocity atol or the
step asked for (dt_given, 0 = automatic) and used (dt), T, status, counters, CPU, error = max over particles of |x - x_ref(T)| in m and, for the knit,
in loop radii r; `measured` = extrapolated for the explicit methods whose cost is only
estimated; cpu_seconds = the integrator's CPU: the run's (run_cpu_seconds) less, for the knit,
its yarn clearance measuring inside the run (clearance_states measurements taking
clearance_cpu_seconds)), references.csv (the reference per case and T and its distance to the same run one
decade looser, and for the knit one decade tighter), ringing.csv (the knit reference's largest
displacement, distance to the settled state and largest speed against time: the time scale the
fixed times were chosen on), manifest.json.
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

CHART = "models/charts/single_tuck.chart"
# SUNDIALS methods with error control that integrate the dynamics, implicit. Left out:
# cvode-bdf-dense (dense LU, ~100x cvode-bdf's CPU in experiments/work_precision; comparison
# only), static (cvode-bdf until its Newton polish, which only acts near equilibrium),
# equilibrium (its t stops when the pins stop, or at once on a knit: after that it follows the
# overdamped flow, not time).
ADAPTIVE = ["cvode-bdf", "cvode-bdf-gmres", "arkode-dirk", "arkode-imex"]
ATOL_PER_RTOL = 1e-3  # atol = 1e-3 rtol (m, m/s): the default pair 1e-6 / 1e-9 of both commands

# Per case: the knitsim command, the fixed times, the reference (cvode-bdf at REF rtol / atol; its
# own error estimated by the distance to the same run at check_rtol, an upper bound if the errors
# fall with rtol, and for the knit by the distance to tight_rtol), the sweeps.
CASES = {
    "two_corner_slack": dict(
        command=["drape", "--scene", "two_corner_slack"],
        # rtol 1e-11 did not reach T = 1000 s in 10 minutes: the error test fights round-off.
        ref_rtol=1e-10, ref_atol=1e-13, check_rtol=1e-9, tight_rtol=None,
        ref_check_max=1e-5,  # m: the study fails if the reference is further from rtol 1e-9
        # The drape command has atol on the velocities too (no --velocity-atol given).
        velocity_atol=False,
        quick=dict(times=[50.0, 100.0], rtols=[1e-4, 1e-6], adaptive=["cvode-bdf"],
                   fixed={"implicit-euler": [10.0, 1.0]}, extrapolate=["euler"]),
        full=dict(times=[50.0, 100.0, 200.0, 1000.0], rtols=[10.0 ** -e for e in range(3, 10)],
                  adaptive=ADAPTIVE,
                  fixed={"implicit-euler": [10.0, 3.0, 1.0, 0.3, 0.1, 0.03],
                         "verlet": [1e-3, 5e-4]},
                  # Explicit methods with stability-bound steps (~2e-6 s for euler on this grid:
                  # ~5e8 steps to 1000 s): one capped run from the start gives CPU per step and
                  # the mean step; the cost to T is extrapolated, the error not measured.
                  extrapolate=["euler", "arkode-erk", "cvode-adams"])),
    "single_tuck": dict(
        command=["knit", "--chart", CHART, "--set", "knit.contact=0"],
        # Positions ~1e-3 m, displacements ~4 r = 3.6e-4 m: atol 1e-14 m is far below the errors
        # resolved; the velocities get the same atol (--velocity-atol; the knit default of 1e-3
        # m/s on the stabilised network does not follow the ringing, see the velocity sweep).
        ref_rtol=1e-10, ref_atol=1e-14, check_rtol=1e-9, tight_rtol=1e-11,
        ref_check_max=1e-10,  # m (~1e-6 r)
        velocity_atol=True,
        # The pull (20 us, the loops moving fastest), the first overshoot (50 us), the ringing
        # decayed to a tenth (200 us), its tail (1 ms, 2e-4 r from the settled state): ringing.csv.
        quick=dict(times=[5e-5, 2e-4], rtols=[1e-4, 1e-6], adaptive=["cvode-bdf"],
                   fixed={"verlet": [0.0]}, extrapolate=[], default_velocity=[]),
        full=dict(times=[2e-5, 5e-5, 2e-4, 1e-3], rtols=[10.0 ** -e for e in range(3, 10)],
                  # On the knit the explicit adaptive methods are measured: their stability-bound
                  # steps (~1e-7..1e-6 s) are a small fraction of the ringing's periods, so a run
                  # to 1 ms takes thousands of steps, not ~1e8.
                  adaptive=ADAPTIVE + ["arkode-erk", "cvode-adams"],
                  # 0 = the automatic step (verlet 4.7e-6 s, euler 3.4e-7 s: their stability
                  # limits with a safety factor); implicit-euler's automatic step on a knit is 1 s.
                  fixed={"implicit-euler": [1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8],
                         "verlet": [0.0, 2e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8],
                         "euler": [0.0, 1e-7, 3e-8, 1e-8]},
                  extrapolate=[],
                  # cvode-bdf with the knit command's own velocity tolerance (1e-3 m/s on the
                  # stabilised network, no --velocity-atol): what a default run gives at fixed times.
                  default_velocity=["cvode-bdf"],
                  # The reference's time scale: cvode-bdf at rtol 1e-8 (error < 1e-6 r) to these
                  # times and to its settled state (no t_max: the run stops at equilibrium).
                  ringing=[1e-6 * t for t in (2, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 60, 70, 80,
                                              90, 100, 120, 140, 160, 180, 200, 250, 300, 400,
                                              500, 600, 800, 1000, 1200, 1500, 2000)])),
}
RINGING_RTOL = 1e-8
EXPLICIT_CAP = 20000  # steps of a capped run (extrapolated explicit methods)


def max_speed(run):
    """Largest |v| over the free points at the end of a run (state.json), m/s."""
    v = json.load(open(os.path.join(run.folder, "state.json")))["v"]
    return max(math.sqrt(v[i] ** 2 + v[i + 1] ** 2 + v[i + 2] ** 2) for i in range(0, len(v), 3))


own_cpu = expkit.integrator_cpu  # the run's CPU less the knit's clearance measuring


def run_case(args, case, c, wall_cap, rows, refs, ringing):
    p = c["quick" if args.quick else "full"]
    times = p["times"]
    r_unit = None  # m: the knit's loop radius (from the reference's summary.json)

    def run(label, integ, opts, T):
        return expkit.run_knitsim(
            args.out, "%s-%s-T%g" % (case, label, T),
            c["command"] + ["--no-pictures", "--integrator", integ,
                            "--set", "run.t_max=%r" % T, "--max-wall", wall_cap] + opts,
            timeout=wall_cap * 3 + 60)

    def tol_opts(rtol, atol):
        return ["--rtol", rtol, "--atol", atol] + (
            ["--velocity-atol", atol] if c["velocity_atol"] else [])

    ref_pos = {}
    for T in times:
        ref = run("reference", "cvode-bdf", tol_opts(c["ref_rtol"], c["ref_atol"]), T)
        s = ref.stats()
        if s.get("status") != "time_limit" or abs(s["t_final"] - T) > 1e-9 * T:
            sys.exit("transient: %s reference to T = %g ended with %s at t = %s"
                     % (case, T, s.get("status"), s.get("t_final")))
        ref_pos[T] = expkit.read_positions(ref)
        if case == "single_tuck":
            r_unit = ref.summary["params"]["loop_radius"]
        per = c["ref_atol"] / c["ref_rtol"]

        def distance(rtol):
            if rtol is None:
                return math.nan
            return expkit.max_position_error(expkit.read_positions(
                run("reference-%g" % rtol, "cvode-bdf", tol_opts(rtol, rtol * per), T)),
                ref_pos[T])
        refs.append(dict(scene=case, time=T, integrator="cvode-bdf", rtol=c["ref_rtol"],
                         atol=c["ref_atol"],
                         velocity_atol=c["ref_atol"], status=s["status"], steps=s["steps"],
                         cpu_seconds=own_cpu(ref.summary), check_rtol=c["check_rtol"],
                         check_distance_m=distance(c["check_rtol"]),
                         tight_rtol=c["tight_rtol"] or math.nan,
                         tight_distance_m=distance(c["tight_rtol"]),
                         loop_radius_m=r_unit or math.nan))
        print("%s reference T = %g s: %d steps, %.3g s CPU; rtol %g run %.3g m away" % (
            case, T, s["steps"], own_cpu(ref.summary), c["check_rtol"],
            refs[-1]["check_distance_m"]), flush=True)

    def record(r, integ, rtol, atol, vatol, dt, T, measured="yes"):
        s = r.stats() if r.summary else {}
        row = dict(scene=case, integrator=integ, rtol=rtol, atol=atol, velocity_atol=vatol,
                   dt_given=dt, dt=dt, time=T,
                   status=s.get("status", "timeout" if r.returncode is None else "not_run"),
                   measured=measured, t_final=s.get("t_final", math.nan),
                   steps=s.get("steps", 0), rhs_evals=s.get("rhs_evals", 0),
                   lin_setups=s.get("lin_setups", 0), err_test_fails=s.get("err_test_fails", 0),
                   restarts=s.get("restarts", 0), cpu_seconds=own_cpu(r.summary),
                   run_cpu_seconds=s.get("cpu_seconds", math.nan),
                   # knit: yarn clearance measurements inside the run and their CPU, which
                   # run_cpu_seconds includes and cpu_seconds (the integrator's) does not
                   **expkit.clearance_columns(r.summary),
                   error_m=math.nan, error_over_r=math.nan)
        if measured == "yes" and r.summary:
            row["dt"] = s.get("dt", dt) or dt
            at_T = row["status"] == "time_limit" and abs(row["t_final"] - T) <= 1e-9 * T
            row["error_m"] = (expkit.max_position_error(expkit.read_positions(r), ref_pos[T])
                              if at_T else math.inf)
            if r_unit:
                row["error_over_r"] = row["error_m"] / r_unit
        rows.append(row)
        print("%-16s %-16s rtol %-8.0e dt %-9.3g T %-6g %-12s cpu %-9.3g err %.3g m" % (
            case, integ, rtol, row["dt"], T, row["status"], row["cpu_seconds"], row["error_m"]),
            flush=True)
        return row

    def sweep(integ, settings, opts_of, label_of, rtol_of, dt_of, vatol_of):
        capped = False
        for x in settings:
            rtol, atol = rtol_of(x), rtol_of(x) * ATOL_PER_RTOL
            for T in times:
                if capped:
                    record(expkit.Run("", None, None, ""), integ, rtol, atol, vatol_of(x),
                           dt_of(x), T, measured="skipped: a looser setting hit the wall cap")
                    continue
                row = record(run(label_of(x), integ, opts_of(x), T), integ, rtol, atol,
                             vatol_of(x), dt_of(x), T)
                capped = row["status"] in ("wall_limit", "timeout")

    for integ in p["adaptive"]:
        sweep(integ, p["rtols"], lambda r: tol_opts(r, r * ATOL_PER_RTOL),
              lambda r, i=integ: "%s-rtol%g" % (i, r), lambda r: r, lambda r: 0.0,
              lambda r: r * ATOL_PER_RTOL)
    # The knit command's own velocity tolerance: no --velocity-atol (velocity_atol recorded as
    # the command reports it in summary.json: options.velocity_atol).
    for integ in p.get("default_velocity", []):
        sweep(integ, p["rtols"], lambda r: ["--rtol", r, "--atol", r * ATOL_PER_RTOL],
              lambda r, i=integ: "%s-default-velocity-atol-rtol%g" % (i, r), lambda r: r,
              lambda r: 0.0, lambda r: 1e-3)
    for integ, dts in p["fixed"].items():
        sweep(integ, dts, lambda d: ["--dt", d], lambda d, i=integ: "%s-dt%g" % (i, d),
              lambda d: 0.0, lambda d: d, lambda d: 0.0)

    # Explicit stability-bound methods (drape): cost per step and mean step of a capped run from
    # the start (default rtol, automatic dt), times T / mean step.
    for integ in p["extrapolate"]:
        r = run(integ + "-capped", integ, ["--max-steps", EXPLICIT_CAP], times[-1])
        s = r.stats()
        mean_h = s["t_final"] / s["steps"]
        cpu_step = s["cpu_seconds"] / s["steps"]
        for T in times:
            row = record(expkit.Run("", None, None, ""), integ, 0.0, 0.0, 0.0, mean_h, T,
                         measured="extrapolated: %d-step run, %.3g s CPU per step"
                                  % (s["steps"], cpu_step))
            row.update(status="extrapolated", steps=round(T / mean_h),
                       cpu_seconds=cpu_step * T / mean_h)

    # The knit reference's time scale (ringing.csv).
    if p.get("ringing"):
        opts = tol_opts(RINGING_RTOL, RINGING_RTOL * ATOL_PER_RTOL)
        settled = expkit.run_knitsim(args.out, case + "-settled",
                                     c["command"] + ["--no-pictures"] + opts)
        end = expkit.read_positions(settled)
        for T in p["ringing"]:
            r = run("ringing", "cvode-bdf", opts, T)
            ringing.append(dict(scene=case, time=T, rtol=RINGING_RTOL,
                                max_displacement_over_r=r.summary["max_displacement_over_r"],
                                distance_to_settled_over_r=expkit.max_position_error(
                                    expkit.read_positions(r), end) / r_unit,
                                max_speed_m_per_s=max_speed(r),
                                residual=r.stats()["residual"],
                                settled_t=settled.stats()["t_final"]))
        print("%s settled (%s) at t = %.3g s; ringing.csv: %d times" % (
            case, settled.stats()["status"], settled.stats()["t_final"], len(p["ringing"])),
            flush=True)
    return times


def main():
    def extra(p):
        p.add_argument("--wall-cap", type=float, default=None,
                       help="wall-clock cap per run, s (default 300, quick 30); an integrator's "
                            "tighter settings are skipped once one run hits it")
        p.add_argument("--only", default=",".join(CASES),
                       help="cases to run, comma-separated (default: %(default)s)")
    args = expkit.parse_args("transient", "transient", extra)
    wall_cap = args.wall_cap or (30.0 if args.quick else 300.0)
    cases = [x for x in args.only.split(",") if x]
    unknown = [x for x in cases if x not in CASES]
    if unknown:
        sys.exit("transient: unknown case(s) %s: choose from %s" % (unknown, ", ".join(CASES)))
    rows, refs, ringing, times = [], [], [], {}
    for case in cases:
        times[case] = run_case(args, case, CASES[case], wall_cap, rows, refs, ringing)

    expkit.write_csv(os.path.join(args.out, "runs.csv"), rows)
    expkit.write_csv(os.path.join(args.out, "references.csv"), refs)
    if ringing:
        expkit.write_csv(os.path.join(args.out, "ringing.csv"), ringing)
    elif os.path.exists(os.path.join(args.out, "ringing.csv")):
        os.remove(os.path.join(args.out, "ringing.csv"))
    expkit.write_manifest(args, "transient", extra={
        "cases": {case: dict(command=CASES[case]["command"], times=times[case],
                             reference_rtol=CASES[case]["ref_rtol"],
                             reference_atol=CASES[case]["ref_atol"],
                             velocity_atol_as_atol=CASES[case]["velocity_atol"])
                  for case in cases},
        "atol_per_rtol": ATOL_PER_RTOL, "ringing_rtol": RINGING_RTOL,
        "wall_cap_seconds": wall_cap, "explicit_cap_steps": EXPLICIT_CAP})
    expkit.finish(args)
    # The study's checks: each reference is converged far below the errors measured, and
    # cvode-bdf's error shrinks from its loosest to its tightest rtol at every time.
    bad = [r for r in refs if not r["check_distance_m"] < CASES[r["scene"]]["ref_check_max"]]
    for case in cases:
        for T in times[case]:
            bdf = [r for r in rows if r["scene"] == case and r["integrator"] == "cvode-bdf"
                   and r["time"] == T and r["measured"] == "yes" and r["velocity_atol"] == r["atol"]]
            if len(bdf) >= 2 and not bdf[-1]["error_m"] < bdf[0]["error_m"]:
                bad.append(dict(case=case, time=T, cvode_bdf_errors=[r["error_m"] for r in bdf]))
    if bad:
        sys.exit("transient: checks failed: %s" % bad)


if __name__ == "__main__":
    main()
