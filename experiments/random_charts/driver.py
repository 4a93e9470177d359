#!/usr/bin/env python3
"""Random charts study: N seeded random 12 x 12 charts (charts.py) through `knitsim knit`, one
CSV row per chart with its run's status, CPU and yarn measures (summary.json's `yarn` block).

    experiments/random_charts/run.sh [--quick] [--out DIR] [--count N] [--seed S]
        [--require-clearance X] [--keep-runs] [-- extra knitsim knit arguments]

Writes DIR/charts/NNN.chart, runs `$KNITSIM knit --chart DIR/charts/NNN.chart [extra]
--no-pictures --quiet --out DIR/runs/NNN` for each (DIR/runs/ removed at the end unless
--keep-runs), then DIR/random_charts.csv and DIR/manifest.json. Defaults: 50 charts, seed 1;
--quick: 5 (the first 5 of the full run).

Exit status: 1 if a run was refused (exit 2: a bug of the chart generator, or a bad extra
argument) or crashed (any exit but 0, 2 and 3; exit 3, any status but equilibrium, is a result
and is recorded), or, with --require-clearance X, if some chart's minimum clearance over its
run is below X r or some designed crossing changed; everything is written first. Else 0:
without --require-clearance the study only reports.
"""
import glob
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)
import charts  # noqa: E402
import expkit  # noqa: E402

NAME = "random_charts"
CSV = "random_charts.csv"
FIELDS = ["chart", "seed", "tucks", "misses", "longest_float", "longest_hold", "tuck_stack",
          "miss_over_tuck", "exit_code", "status", "clearance_min_over_r",
          "clearance_end_over_r", "clearance_rest_over_r", "clearance_min_resolution_over_r",
          "crossings_changed", "crossings_designed", "clearance_min_t", "clearance_min_check",
          "max_displacement_over_r", "pattern_misses",
          "t_final", "steps", "cpu_seconds", "run_cpu_seconds", "clearance_cpu_seconds",
          "wall_seconds", "error", "rows"]


def add_arguments(p):
    p.add_argument("--count", type=int, default=None,
                   help="number of charts (default 50; --quick: 5)")
    p.add_argument("--seed", type=int, default=1, help="seed of the chart generator (default 1)")
    p.add_argument("--require-clearance", type=float, default=None, metavar="X",
                   help="exit 1 if a chart's minimum clearance over its run is below X r or a "
                        "designed crossing changed (default: report only)")


def split_extra(argv):
    """(the study's arguments, the knitsim arguments after '--')."""
    if "--" in argv:
        k = argv.index("--")
        return argv[:k], argv[k + 1:]
    return argv, []


def run_chart(out, name, chart_path, extra):
    """One knitsim knit run: (exit code, summary or None, stderr, process CPU s, wall s)."""
    folder = os.path.join(out, "runs", name)
    cmd = ([expkit.knitsim_path(), "knit", "--chart", chart_path] + extra +
           ["--no-pictures", "--quiet", "--out", folder])
    summary_path = os.path.join(folder, "summary.json")
    if os.path.exists(summary_path):
        os.remove(summary_path)
    cpu0, wall0 = expkit.cpu_children(), time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    cpu, wall = expkit.cpu_children() - cpu0, time.monotonic() - wall0
    summary = None
    if p.returncode in (0, 3) and os.path.exists(summary_path):
        with open(summary_path) as f:
            summary = json.load(f)
        expkit.note_build(os.path.join(folder, "manifest.json"))
    return p.returncode, summary, p.stderr, cpu, wall


def row_of(name, seed, chart, code, summary, stderr, cpu, wall):
    r = {"chart": name, "seed": seed}
    r.update(charts.features(chart))
    r.update({"exit_code": code, "cpu_seconds": cpu, "wall_seconds": wall, "error": "",
              "rows": "/".join(charts.drawn(chart))})
    if summary is not None:
        stats, yarn = summary.get("stats", {}), summary.get("yarn", {})
        r["status"] = summary.get("status", stats.get("status", ""))
        for k in ("clearance_min_over_r", "clearance_end_over_r", "clearance_rest_over_r",
                  "clearance_min_resolution_over_r", "crossings_changed", "crossings_designed",
                  "clearance_min_t", "clearance_min_check", "clearance_cpu_seconds"):
            r[k] = yarn.get(k, "")
        r["max_displacement_over_r"] = summary.get("max_displacement_over_r", "")
        r["pattern_misses"] = (summary.get("contact") or {}).get("pattern_misses", "")
        r["t_final"] = summary.get("t_final", "")
        r["steps"] = stats.get("steps", "")
        r["run_cpu_seconds"] = stats.get("cpu_seconds", "")
    else:
        r["status"] = ("refused" if code == 2 else
                       "no summary.json" if code in (0, 3) else
                       "signal %d" % -code if code < 0 else "crashed")
        lines = [ln for ln in stderr.strip().splitlines() if ln.strip()]
        r["error"] = lines[-1] if lines else "exit %d, no message" % code
    return r


def main():
    argv, extra = split_extra(sys.argv[1:])
    command = " ".join(["experiments/%s/run.sh" % NAME] + sys.argv[1:])
    sys.argv = [sys.argv[0]] + argv
    args = expkit.parse_args(NAME, NAME, add_arguments)
    if args.reuse:
        sys.exit("random_charts: --reuse is not supported (a full run takes about a minute)")
    count = args.count if args.count is not None else (5 if args.quick else 50)
    if count < 1:
        sys.exit("random_charts: --count must be >= 1")

    chart_dir = os.path.join(args.out, "charts")
    for old in glob.glob(os.path.join(chart_dir, "*.chart")):
        os.remove(old)
    written = charts.write_charts(chart_dir, count, args.seed)

    rows, wall0 = [], time.monotonic()
    for name, path, chart in written:
        code, summary, stderr, cpu, wall = run_chart(args.out, name, path, extra)
        r = row_of(name, args.seed, chart, code, summary, stderr, cpu, wall)
        rows.append(r)
        if summary is not None:
            print("%s: %s (exit %d), tucks %d, misses %d, min clearance %s r, crossings changed "
                  "%s of %s, %.2f s CPU"
                  % (name, r["status"], code, r["tucks"], r["misses"],
                     expkit.num(r["clearance_min_over_r"]), r["crossings_changed"],
                     r["crossings_designed"], cpu), flush=True)
        else:
            print("%s: %s (exit %d): %s" % (name, r["status"], code, r["error"]), flush=True)
    wall = time.monotonic() - wall0

    expkit.write_csv(os.path.join(args.out, CSV), rows, FIELDS)
    cpu = sum(r["cpu_seconds"] for r in rows)
    expkit.write_manifest(args, NAME, command=command, extra={
        "count": count, "seed": args.seed, "wales": charts.WALES, "courses": charts.COURSES,
        "probability": charts.PROBABILITY, "knitsim_args": extra,
        "require_clearance": args.require_clearance,
        "cpu_seconds": cpu, "wall_seconds": wall})
    expkit.finish(args)

    failures = []
    for r in rows:
        if r["exit_code"] not in (0, 3) or r["status"] == "no summary.json":
            failures.append("%s: %s (exit %d): %s" % (r["chart"], r["status"], r["exit_code"],
                                                       r["error"]))
    if args.require_clearance is not None:
        x = args.require_clearance
        for r in rows:
            c = r.get("clearance_min_over_r", "")
            if c == "" or not (isinstance(c, (int, float)) and math.isfinite(c)):
                continue  # a run without a summary is a failure above
            if c < x or r["crossings_changed"]:
                failures.append("%s: minimum clearance %s r (required %g r), %s of %s designed "
                                "crossings changed"
                                % (r["chart"], expkit.num(c), x, r["crossings_changed"],
                                   r["crossings_designed"]))
    print("random_charts: %d charts, %.1f s CPU, %.1f s wall; %s" %
          (count, cpu, wall, os.path.join(args.out, CSV)))
    for f in failures:
        print("random_charts: " + f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
