"""Shared pieces of the experiment drivers (experiments/*/driver.py): run the knitsim binary,
read its outputs, compare states, write raw CSV and the manifest (STYLE.md practice 10).

Only the Python standard library: drivers must run under Debian's /usr/bin/python3 without
anything installed; the plot scripts alone need matplotlib.

Conventions of every driver using it:
  * command line `--quick` (seconds to a minute, exercised by CI) and `--out DIR`;
  * the knitsim binary is $KNITSIM, else <repo>/build/knitsim;
  * each knitsim run writes into DIR/runs/<label>/ (deleted at the end unless --keep-runs);
  * DIR ends up with the raw CSV files, manifest.json and (after the plot script) PNGs.
"""
import argparse
import csv
import datetime
import json
import math
import os
import resource
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


REUSE = False  # set by parse_args (--reuse)


def knitsim_path():
    path = os.environ.get("KNITSIM", os.path.join(ROOT, "build", "knitsim"))
    if not os.access(path, os.X_OK):
        sys.exit("%s not built (run ./run.sh --build-only, or set KNITSIM)" % path)
    return path


def parse_args(name, default_out, add_arguments=None):
    """The common command line; `add_arguments(parser)` adds a study's own flags."""
    p = argparse.ArgumentParser(prog="experiments/%s/run.sh" % name)
    p.add_argument("--quick", action="store_true", help="small sweep (seconds to a minute)")
    p.add_argument("--out", default=os.path.join(ROOT, "out", "experiments", default_out),
                   help="output folder (CSV, manifest.json, PNG)")
    p.add_argument("--keep-runs", action="store_true",
                   help="keep every knitsim output folder under OUT/runs/")
    p.add_argument("--reuse", action="store_true",
                   help="reuse a run found in OUT/runs/ made by the same knitsim command (to "
                        "resume an interrupted study; implies --keep-runs)")
    if add_arguments:
        add_arguments(p)
    a = p.parse_args()
    a.out = os.path.abspath(a.out)
    a.keep_runs = a.keep_runs or a.reuse
    global REUSE
    REUSE = a.reuse
    os.makedirs(os.path.join(a.out, "runs"), exist_ok=True)
    return a


class Run:
    """One knitsim invocation: its folder, exit status and summary.json (None if absent)."""

    def __init__(self, folder, returncode, summary, stderr):
        self.folder, self.returncode = folder, returncode
        self.summary, self.stderr = summary, stderr

    def stats(self):
        """The run statistics (drape: top level of summary.json; knit: its "stats")."""
        s = self.summary or {}
        return s.get("stats", s)


def integrator_cpu(summary):
    """The integrator's CPU seconds of a run from its summary.json: the run's cpu_seconds (drape:
    top level; knit: "stats") less, for the knit, the yarn clearance measuring `knitsim knit`
    does inside the run (yarn.clearance_cpu_seconds), which the run's figure includes."""
    summary = summary or {}
    measuring = (summary.get("yarn") or {}).get("clearance_cpu_seconds", 0.0)
    return summary.get("stats", summary).get("cpu_seconds", math.nan) - measuring


def clearance_columns(summary):
    """runs.csv's clearance_states and clearance_cpu_seconds: the knit's yarn clearance
    measurements inside the run and their CPU (empty for a drape)."""
    yarn = (summary or {}).get("yarn") or {}
    return dict(clearance_states=yarn.get("clearance_measured_states", ""),
                clearance_cpu_seconds=yarn.get("clearance_cpu_seconds", ""))


BUILD_FIELDS = ("git_commit", "build_type", "compiler", "libraries")
FIRST_BUILD = None  # the build stamp (BUILD_FIELDS) in the manifest of the study's first run


def note_build(manifest_path):
    """Keep the build stamp of the first run that wrote a manifest (FIRST_BUILD)."""
    global FIRST_BUILD
    if FIRST_BUILD is None and os.path.exists(manifest_path):
        km = json.load(open(manifest_path))
        FIRST_BUILD = {k: km.get(k) for k in BUILD_FIELDS}


# `knitsim drape` runs go through the Python module of the same build (docs/python.md) when it
# is there: <folder of the binary>/python, so that KNITSIM=<another build> runs that build's
# module or none. The same numbers and files (ctest python_module), without a process per run.
# KNITSIM_EXPKIT_PROCESSES=1 runs every drape as a process instead.
_MODULE = []  # [the module, or None], looked up once


def _module():
    if not _MODULE:
        module = None
        folder = os.path.join(os.path.dirname(knitsim_path()), "python")
        if os.environ.get("KNITSIM_EXPKIT_PROCESSES") != "1" and os.path.isdir(folder):
            sys.path.insert(0, folder)
            try:
                import knitsim as module
            except ImportError:
                module = None
            finally:
                sys.path.remove(folder)
        _MODULE.append(module)
    return _MODULE[0]


# drape's flags the module takes, and its run options by flag (docs/python.md).
_DRAPE_RUN_FLAGS = {"--rtol", "--atol", "--velocity-atol", "--dt", "--max-order", "--max-steps",
                    "--max-wall", "--max-restarts", "--newton-solver", "--factorization",
                    "--gmres-preconditioner", "--krylov-dim", "--eps-lin"}


def _drape_in_process(args, folder):
    """`knitsim drape ARGS --out FOLDER` through the module: the Run, or None where the module is
    absent or ARGS hold a flag it does not take (--continue, --step-history): then the binary
    runs it."""
    knitsim = _module()
    if knitsim is None or not args or args[0] != "drape":
        return None
    call = dict(scene="four_corner", overrides=[], integrator=None, target=None)
    options, pictures, i = {}, True, 1
    while i < len(args):
        flag = args[i]
        if flag in ("--no-pictures", "--quiet"):
            pictures = pictures and flag != "--no-pictures"
            i += 1
            continue
        if i + 1 >= len(args):
            return None
        value = args[i + 1]
        if flag == "--set":
            call["overrides"].append(value)
        elif flag in ("--scene", "--integrator", "--target"):
            call[flag[2:]] = value
        elif flag in _DRAPE_RUN_FLAGS:
            options[flag[2:].replace("-", "_")] = value
        else:
            return None
        i += 2
    try:
        result = knitsim.drape(**call, **options)
    except ValueError as e:  # bad input, as the binary's exit 2
        sys.exit("knitsim failed (bad input): drape %s\n%s" % (" ".join(args[1:]), e))
    result.write(folder, pictures=pictures)
    summary_path = os.path.join(folder, "summary.json")
    note_build(os.path.join(folder, "manifest.json"))
    return Run(folder, 0 if result.status == "equilibrium" else 3,
               json.load(open(summary_path)), "")


def run_knitsim(out, label, args, timeout=None):
    """knitsim ARGS --quiet --out OUT/runs/LABEL. Exit 0 (equilibrium) and 3 (another status,
    outputs written) are results; anything else (bad input) stops the driver. A drape runs
    through the module where it can (_drape_in_process), unless a timeout is asked for or the
    run may be reused (--reuse)."""
    folder = os.path.join(out, "runs", label)
    args = [str(a) for a in args]
    # The studies measure whole sheets unless a row names a reduction: knitsim's default
    # model.symmetry = auto would otherwise reduce drapes and fits behind their backs.
    if args and args[0] in ("drape", "fit") and not any("model.symmetry" in a for a in args):
        args += ["--set", "model.symmetry=none"]
    cmd = [knitsim_path()] + args + ["--quiet", "--out", folder]
    summary_path = os.path.join(folder, "summary.json")
    manifest_path = os.path.join(folder, "manifest.json")
    if REUSE and os.path.exists(summary_path) and os.path.exists(manifest_path) and \
            json.load(open(manifest_path)).get("command_line") == " ".join(cmd):
        summary = json.load(open(summary_path))
        status = summary.get("stats", summary).get("status")
        note_build(manifest_path)
        return Run(folder, 0 if status == "equilibrium" else 3, summary, "")
    shutil.rmtree(folder, ignore_errors=True)
    if timeout is None and not REUSE:
        run = _drape_in_process(args, folder)
        if run is not None:
            return run
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return Run(folder, None, None, "timeout after %s s" % timeout)
    if p.returncode not in (0, 3):
        sys.exit("knitsim failed (exit %d): %s\n%s" % (p.returncode, " ".join(cmd), p.stderr))
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else None
    note_build(manifest_path)
    return Run(folder, p.returncode, summary, p.stderr)


def cpu_children():
    """User + system CPU seconds of this process's finished children (getrusage): the cost of
    a knitsim run that reports no cpu_seconds of its own (e.g. `knitsim fit`), by difference."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def read_positions(run):
    """Particle positions of a drape (nodes.csv) or knit (points.csv) run: {id: (x, y, z)} in m."""
    for name in ("nodes.csv", "points.csv"):
        path = os.path.join(run.folder, name)
        if os.path.exists(path):
            return {int(r["id"]): (float(r["x"]), float(r["y"]), float(r["z"]))
                    for r in csv.DictReader(open(path))}
    raise FileNotFoundError("no nodes.csv or points.csv in " + run.folder)


def max_position_error(a, b):
    """max over particles of |x_a - x_b| (Euclidean), m; inf if the particle sets differ or a
    position is not finite."""
    if set(a) != set(b):
        return math.inf
    err = 0.0
    for k, pa in a.items():
        d = math.sqrt(sum((u - v) ** 2 for u, v in zip(pa, b[k])))
        if not math.isfinite(d):
            return math.inf
        err = max(err, d)
    return err


def write_target_from(run, path):
    """A coefficient target (src/fit/targets.hpp CSV) holding the edge coefficients of `run`."""
    s = run.summary
    with open(path, "w") as f:
        f.write("# edge coefficients of %s (%s)\n" % (run.folder, s["integrator"]))
        f.write("scene,edge,kind,a,b\n")
        for edge, coeffs in sorted(s["edge_coefficients"].items()):
            for i, c in enumerate(coeffs):
                f.write("%s,%s,coeff,%d,%r\n" % (s["scene"], edge, i, c))


def coefficient_error(a, b):
    """Eq. 5 between two edge-coefficient sets ({edge: [p0..p4]}): 100 sqrt(mean sq. diff), %."""
    d = [(x - y) ** 2 for e in a for x, y in zip(a[e], b[e])]
    return 100.0 * math.sqrt(sum(d) / len(d))


def write_csv(path, rows, fields=None):
    fields = fields or list(rows[0].keys())
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})


def loglog_slope(xs, ys):
    """Least-squares slope of log y against log x over the finite positive pairs; nan if < 2."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys)
           if x > 0 and y > 0 and math.isfinite(x) and math.isfinite(y)]
    if len(pts) < 2:
        return math.nan
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else math.nan


def write_manifest(args, name, sample_run=None, extra=None, command=None):
    """OUT/manifest.json: study, command line (`command`, else the study's run.sh with this
    process's arguments), git commit, knitsim binary and its own manifest (build commit and
    type, libraries: from `sample_run`, else from the study's first run), machine load, and the
    study's parameters (`extra`)."""
    try:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip() or "unknown"
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain"],
                               capture_output=True, text=True).stdout.strip() != ""
    except OSError:
        commit, dirty = "unknown", False
    m = {"experiment": name,
         "command": command or " ".join(["experiments/%s/run.sh" % name] + sys.argv[1:]),
         "quick": args.quick,
         "git_commit": commit + ("+dirty" if dirty else ""),
         "knitsim": knitsim_path(),
         "created_utc": datetime.datetime.utcnow().isoformat(timespec="seconds") + "Z",
         "nproc": os.cpu_count(),
         "load_average": os.getloadavg()}
    kp = os.path.join(sample_run.folder, "manifest.json") if sample_run is not None else ""
    if os.path.exists(kp):
        km = json.load(open(kp))
        m["knitsim_build"] = {k: km.get(k) for k in BUILD_FIELDS}
    elif FIRST_BUILD is not None:
        m["knitsim_build"] = FIRST_BUILD
    m.update(extra or {})
    with open(os.path.join(args.out, "manifest.json"), "w") as f:
        json.dump(m, f, indent=2)


def finish(args):
    """Remove the per-run folders unless --keep-runs."""
    if not args.keep_runs:
        shutil.rmtree(os.path.join(args.out, "runs"), ignore_errors=True)


# --- Generated summaries: the tables of figures a study's README points at ---------------------
#
# Every study has a script experiments/<study>/summary.py that reads only the study's CSV files
# (and manifest.json) in a folder and writes the folder's summary.md: markdown tables of the
# figures its README discusses. No table of figures in a README is typed by hand; the README links
# to summary.md instead. experiments/tables.sh rewrites every committed summary.md from the
# committed CSV; experiments/check_tables.py fails when one differs from what its CSV gives.
# The output is deterministic (no timestamps, no machine state), so regenerating is idempotent.

# Where each study keeps its committed data (default: results/).
COMMITTED = {"scaling": "data", "identifiability": "."}


def committed_dir(study):
    """The folder of the committed CSV files of experiments/<study>."""
    return os.path.normpath(os.path.join(ROOT, "experiments", study,
                                         COMMITTED.get(study, "results")))


def read_rows(folder, name):
    """The rows of FOLDER/NAME as dicts of strings; [] if the file does not exist."""
    path = os.path.join(folder, name)
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(row for row in f if not row.startswith("#")))


def read_json(folder, name):
    """FOLDER/NAME parsed, or {} if it does not exist."""
    path = os.path.join(folder, name)
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)


def num(x, digits=3, dash="—", exp=False):
    """A number for a table: `digits` significant digits in %g style with a compact exponent
    (2.95e3, 2.4e-11, 0.0201), always in exponent form with `exp` (1e-4, 2.5e-7: tolerances);
    `dash` for an empty or nan value. Accepts strings (CSV fields)."""
    if x is None or x == "":
        return dash
    x = float(x)
    if math.isnan(x):
        return dash
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if exp and x != 0:
        mant, e = ("%.*e" % (digits - 1, x)).split("e")
        if "." in mant:
            mant = mant.rstrip("0").rstrip(".")
        return "%se%d" % (mant, int(e))
    s = "%.*g" % (digits, x)
    if "e" in s:
        mant, e = s.split("e")
        s = "%se%d" % (mant, int(e))
    return s


def sci(x, digits=3, dash="—"):
    """A number in exponent form with `digits` significant digits kept (8.333e-6, 5.000e-6)."""
    if x is None or x == "":
        return dash
    x = float(x)
    if math.isnan(x):
        return dash
    if math.isinf(x):
        return "inf"
    if x == 0:
        return "0"
    mant, exp = ("%.*e" % (digits - 1, x)).split("e")
    return "%se%d" % (mant, int(exp))


def span(values, fmt=num, sep="–"):
    """'lo–hi' of the finite values formatted by `fmt` (one value if they are equal); '—' if
    none."""
    vs = sorted(float(v) for v in values if v not in (None, "") and math.isfinite(float(v)))
    if not vs:
        return "—"
    lo, hi = fmt(vs[0]), fmt(vs[-1])
    return lo if lo == hi else lo + sep + hi


def median(values):
    """Median of numbers (statistics.median, floats)."""
    import statistics
    return statistics.median(float(v) for v in values)


def percentile(values, q):
    """The q-th percentile with linear interpolation between order statistics (numpy's
    default)."""
    vs = sorted(float(v) for v in values)
    if not vs:
        return math.nan
    pos = (len(vs) - 1) * q / 100.0
    lo = math.floor(pos)
    hi = min(lo + 1, len(vs) - 1)
    return vs[lo] + (vs[hi] - vs[lo]) * (pos - lo)


def md_table(header, rows):
    """A markdown table: header (list of str) and rows (lists of values, str()-ed; '|' in a cell
    is escaped)."""
    def cell(v):
        return str(v).replace("|", "\\|").replace("\n", " ")
    lines = ["| " + " | ".join(cell(h) for h in header) + " |",
             "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(v) for v in r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def summary_text(title, script, sources, sections):
    """summary.md: a title, the generated-file note (script, sources) and the sections, each
    (heading, markdown body); a section with an empty body is left out."""
    parts = ["# %s\n" % title,
             "<!-- generated by %s from %s: do not edit; regenerate with experiments/tables.sh "
             "(checked by experiments/check_tables.py) -->\n" % (script, ", ".join(sources))]
    for heading, body in sections:
        if body:
            parts.append("## %s\n\n%s" % (heading, body.rstrip("\n") + "\n"))
    return "\n".join(parts)


def summary_main(study, build, argv=None, script=None, folder=None):
    """The command line of every experiments/<study>/summary.py (and paper_repro/knit's):

        summary.py [DIR] [--output FILE]

    DIR: the folder whose CSV files are read (default: `folder`, else the study's committed
    folder, committed_dir(study)); FILE: where summary.md goes (default DIR/summary.md).
    `script`: the script's path from the root (default experiments/<study>/summary.py).
    `build(DIR)` returns (title, sources, sections) for summary_text; returns the text written."""
    script = script or "experiments/%s/summary.py" % study
    p = argparse.ArgumentParser(prog=script,
                                description="Write the study's summary.md (tables of figures) "
                                            "from the CSV files in DIR.")
    p.add_argument("dir", nargs="?", default=folder or committed_dir(study),
                   help="folder with the study's CSV files (default: the committed one)")
    p.add_argument("--output", help="file to write (default DIR/summary.md)")
    a = p.parse_args(argv)
    title, sources, sections = build(a.dir)
    text = summary_text(title, script, sources, sections)
    output = a.output or os.path.join(a.dir, "summary.md")
    with open(output, "w") as f:
        f.write(text)
    print("%s: wrote %s" % (study, output))
    return text


def provenance(manifest, source="manifest.json"):
    """Markdown bullets of a study's manifest.json: the command, the knitsim binary and its build
    stamp, when it ran, the machine (nproc, load average), a note; '' for an empty manifest."""
    if not manifest:
        return ""
    lines = []
    cmd = manifest.get("command") or manifest.get("command_line")
    if cmd:
        lines.append("- command: `%s`" % cmd)
    for c in manifest.get("commands", []):
        lines.append("- command: `%s`" % c)
    if manifest.get("knitsim"):
        lines.append("- knitsim binary: `%s`" % manifest["knitsim"])
    if "knitsim_build" in manifest:
        build, head = manifest["knitsim_build"] or {}, manifest.get("git_commit")
    elif "command_line" in manifest:  # the manifest of a knitsim program itself
        build, head = manifest, None
    else:
        build, head = {}, manifest.get("git_commit")
    if build.get("git_commit"):
        commit = build["git_commit"]
        lines.append("- knitsim build: %s, %s, %s"
                     % ("commit not recorded" if commit == "unknown" else "commit " + commit,
                        build.get("build_type") or "?", build.get("compiler") or "?"))
    if head:
        lines.append("- repository HEAD when the manifest was written: %s" % head)
    if manifest.get("created_utc"):
        lines.append("- written (UTC): %s" % manifest["created_utc"])
    la = manifest.get("load_average")
    if isinstance(la, list):
        lines.append("- machine: %s cores, load average %s (1, 5, 15 min)"
                     % (manifest.get("nproc", "?"), " / ".join("%.2f" % v for v in la)))
    elif la:
        lines.append("- machine: load %s" % la)
    if manifest.get("note"):
        lines.append("- note: %s" % manifest["note"])
    if manifest.get("not_measured"):
        lines.append("- not measured: %s" % manifest["not_measured"])
    return "From `%s`:\n\n" % source + "\n".join(lines) + "\n" if lines else ""
