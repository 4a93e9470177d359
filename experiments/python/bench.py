#!/usr/bin/python3
"""The Python module's overhead and its threads (experiments/python/README.md): a sweep of
four_corner drapes (model.stiffness evenly from 500 to 1200 N/m) run

  py1   from Python, knitsim.drape in a loop (this process; reads each result's centre sag),
  cpp1  by a C++ loop calling the module's entry point, src/python/drape_call.hpp
        (knitsim_python_bench: the same requests and results, no files, no Python),
  py2   from Python on two threads (run k on thread k mod 2),
  cpp2  by the C++ loop on two threads,
  cli   by one `knitsim drape --no-pictures --quiet` process per drape (--cli-calls of them),
        all into one --out folder (each run replaces the files of the one before),

each repeated --reps times, in that order within a repeat (paired). Once, after the first
repeat, where a CLI call's time goes (--cli-calls of each):

  start      `knitsim --version` processes: the binary's start and exit, nothing run;
  first      `knitsim_python_bench --runs 1` processes, timed inside (the call only): a drape
             in a fresh process, without its files;
  cli_tmpfs  the cli sweep with --out in /dev/shm (a memory file system; skipped without it);
  cli_fresh  the cli sweep with a new --out folder per call (no file replaced).
 Writes OUT/runs.csv (one row
per method and repeat: wall and CPU seconds of the whole sweep) and OUT/manifest.json;
summary.py makes the tables.

    experiments/python/run.sh [--quick] [--out DIR] [--runs N] [--reps R] [--cli-calls C]

Needs the module (build/python, or $KNITSIM_PYTHON) and build/knitsim_python_bench
($KNITSIM_PYTHON_BENCH): both are built by ./run.sh --build-only where pybind11 is found.
"""
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
import expkit  # noqa: E402

sys.path.insert(0, os.environ.get("KNITSIM_PYTHON", os.path.join(expkit.ROOT, "build", "python")))
try:
    import knitsim  # noqa: E402
except ImportError as e:
    sys.exit("experiments/python: the knitsim module is not built (%s); ./run.sh --build-only" % e)


def stiffness(k, n):
    """The k-th stiffness of an n-run sweep (the C++ loop computes the same doubles)."""
    return 500.0 + 700.0 * k / (n - 1 if n > 1 else 1)


def python_sweep(n, threads):
    sags = [None] * n

    def work(t):
        for k in range(t, n, threads):
            sags[k] = knitsim.drape("four_corner", {"model.stiffness": stiffness(k, n)}).centre_sag

    cpu, wall = time.process_time(), time.perf_counter()
    if threads == 1:
        work(0)
    else:
        pool = [threading.Thread(target=work, args=(t,)) for t in range(threads)]
        for p in pool:
            p.start()
        for p in pool:
            p.join()
    return time.perf_counter() - wall, time.process_time() - cpu, sum(sags)


def cpp_sweep(bench, n, threads):
    p = subprocess.run([bench, "--runs", str(n), "--threads", str(threads)], capture_output=True,
                       text=True, check=True)
    r = json.loads(p.stdout)
    return r["seconds"], r["cpu_seconds"], r["sag_sum"]


def children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cli_sweep(cli, n, work, fresh=False):
    cpu, wall = children(), time.perf_counter()
    for k in range(n):
        out = os.path.join(work, "run%d" % k if fresh else "run")
        subprocess.run([cli, "drape", "--set", "model.stiffness=%r" % stiffness(k, n),
                        "--no-pictures", "--quiet", "--out", out], check=True)
    return time.perf_counter() - wall, children() - cpu, float("nan")


def start_sweep(cli, n):
    cpu, wall = children(), time.perf_counter()
    for _ in range(n):
        subprocess.run([cli, "--version"], check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - wall, children() - cpu, float("nan")


def first_call_sweep(bench, n):
    """n fresh processes of one drape each, timed inside: the call, not the process."""
    wall = cpu = 0.0
    for _ in range(n):
        w, c, _ = cpp_sweep(bench, 1, 1)
        wall, cpu = wall + w, cpu + c
    return wall, cpu, float("nan")


def main():
    def extra(p):
        p.add_argument("--runs", type=int, help="drapes per sweep (default 1000; quick 100)")
        p.add_argument("--reps", type=int, help="repeats of every sweep (default 5; quick 2)")
        p.add_argument("--cli-calls", type=int,
                       help="drapes of the CLI sweep (default --runs; quick 20); run once")
    a = expkit.parse_args("python", "python", extra)
    runs = a.runs or (100 if a.quick else 1000)
    reps = a.reps or (2 if a.quick else 5)
    cli_calls = a.cli_calls or (20 if a.quick else runs)
    cli = expkit.knitsim_path()
    bench = os.environ.get("KNITSIM_PYTHON_BENCH",
                           os.path.join(os.path.dirname(cli), "knitsim_python_bench"))
    if not os.access(bench, os.X_OK):
        sys.exit("experiments/python: %s not built (./run.sh --build-only)" % bench)

    rows = []

    def record(rep, method, n, threads, measured):
        wall, cpu, sag_sum = measured
        rows.append(dict(rep=rep, method=method, runs=n, threads=threads,
                         wall_seconds="%.6f" % wall, cpu_seconds="%.6f" % cpu))
        print("rep %d %-4s %5d drapes: %.3f s wall, %.3f s CPU" % (rep, method, n, wall, cpu),
              flush=True)
        return sag_sum

    knitsim.drape()  # the module's first call (loads what a drape needs), outside the timings
    with tempfile.TemporaryDirectory() as work:
        for rep in range(1, reps + 1):
            sums = [record(rep, "py1", runs, 1, python_sweep(runs, 1)),
                    record(rep, "cpp1", runs, 1, cpp_sweep(bench, runs, 1)),
                    record(rep, "py2", runs, 2, python_sweep(runs, 2)),
                    record(rep, "cpp2", runs, 2, cpp_sweep(bench, runs, 2))]
            # The same drapes: the same sags, bit for bit, from every loop.
            if len(set(sums)) != 1:
                sys.exit("experiments/python: the loops disagree: sum of sags %r" % sums)
            if rep == 1:
                record(rep, "cli", cli_calls, 1, cli_sweep(cli, cli_calls, work))
                record(rep, "start", cli_calls, 1, start_sweep(cli, cli_calls))
                record(rep, "first", cli_calls, 1, first_call_sweep(bench, cli_calls))
                if os.access("/dev/shm", os.W_OK):
                    with tempfile.TemporaryDirectory(dir="/dev/shm") as shm:
                        record(rep, "cli_tmpfs", cli_calls, 1, cli_sweep(cli, cli_calls, shm))
                with tempfile.TemporaryDirectory() as fresh:
                    record(rep, "cli_fresh", cli_calls, 1,
                           cli_sweep(cli, cli_calls, fresh, fresh=True))
    expkit.write_csv(os.path.join(a.out, "runs.csv"), rows)
    expkit.write_manifest(a, "python", extra={
        "runs": runs, "reps": reps, "cli_calls": cli_calls, "python": sys.executable,
        "module": knitsim.__file__, "module_build": knitsim.build["version"],
        "bench": bench, "scene": "four_corner",
        "sweep": "model.stiffness 500..1200 N/m, evenly"})
    expkit.finish(a)
    subprocess.run([sys.executable, os.path.join(HERE, "summary.py"), a.out], check=True)


if __name__ == "__main__":
    main()
