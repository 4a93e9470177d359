#!/usr/bin/python3
"""Tables of experiments/python from its CSV file only (runs.csv, manifest.json) -> summary.md;
the README points at them. Standard library only.

    summary.py [DIR] [--output FILE]     (default DIR: experiments/python/results)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from expkit import md_table, median, num, provenance, read_json, read_rows, summary_main  # noqa: E402

LABELS = {"py1": "Python, knitsim.drape in a loop", "cpp1": "C++ loop over the same entry point",
          "py2": "Python, two threads", "cpp2": "C++ loop, two threads",
          "cli": "one knitsim process per drape",
          "start": "knitsim --version processes (start and exit only)",
          "first": "one drape in a fresh process, timed inside (no files)",
          "cli_tmpfs": "cli with --out in /dev/shm (memory file system)",
          "cli_fresh": "cli with a new --out folder per call"}


def build(out):
    rows = read_rows(out, "runs.csv")
    by = {}
    for r in rows:
        by.setdefault(r["method"], []).append(r)

    def med(method, field):
        values = [float(r[field]) / int(r["runs"]) for r in by.get(method, [])]
        return median(values) if values else float("nan")

    table = []
    for m in ("py1", "cpp1", "py2", "cpp2", "cli", "start", "first", "cli_tmpfs", "cli_fresh"):
        if m not in by:
            continue
        table.append([m, LABELS[m], by[m][0]["runs"], len(by[m]),
                      num(1e3 * med(m, "wall_seconds")), num(1e3 * med(m, "cpu_seconds"))])
    sections = [("Per drape (runs.csv)",
                 "Medians over the repeats of each sweep's wall and CPU time divided by its "
                 "drapes (CPU: the whole process, all threads; for the CLI, the children's).\n\n"
                 + md_table(["method", "what", "drapes per sweep", "repeats",
                             "wall per drape (ms)", "CPU per drape (ms)"], table))]

    def ratio(a, b, field):
        return med(a, field) / med(b, field)

    # Paired ratios: each repeat's Python sweep over the C++ sweep of the same repeat.
    def paired(a, b, field):
        pairs = [float(x[field]) / float(y[field]) for x, y in zip(by.get(a, []), by.get(b, []))]
        return median(pairs) if pairs else float("nan")

    targets = [
        ["Python / C++ loop, one thread", num(paired("py1", "cpp1", "wall_seconds")),
         num(paired("py1", "cpp1", "cpu_seconds")), "<= 1.2"],
        ["CLI processes / Python loop", num(ratio("cli", "py1", "wall_seconds")),
         num(ratio("cli", "py1", "cpu_seconds")), ">= 10"],
        ["Python: one thread / two threads (speed-up)", num(paired("py1", "py2", "wall_seconds")),
         "—", ">= 1.7"],
        ["C++: one thread / two threads (speed-up)", num(paired("cpp1", "cpp2", "wall_seconds")),
         "—", "(the machine's own bound)"],
    ]
    sections.append(("Against the issue's targets",
                     "Python / C++ and the speed-ups: medians of the repeats' paired ratios; the "
                     "CLI: per-drape medians (it runs once).\n\n"
                     + md_table(["ratio", "wall", "CPU", "target"], targets)))
    if all(m in by for m in ("cli", "start", "first", "cli_tmpfs", "cli_fresh")):
        def part(what, plus, minus=()):
            return [what] + [num(1e3 * (sum(med(m, f) for m in plus) -
                                        sum(med(m, f) for m in minus)))
                             for f in ("wall_seconds", "cpu_seconds")]
        parts = [
            part("the process's start and exit (start)", ["start"]),
            part("the drape's call in a fresh process (first)", ["first"]),
            part("  of which what a warm call costs too (cpp1)", ["cpp1"]),
            part("  of which the first call's own: sparsity analysis not yet memoised, a "
                 "fresh heap, cold caches (first - cpp1)", ["first"], ["cpp1"]),
            part("the command's own work: flags, folder checks, formatting and writing the "
                 "files to memory (cli_tmpfs - start - first)", ["cli_tmpfs"],
                 ["start", "first"]),
            part("the files on the disk's file system, not in memory (cli_fresh - cli_tmpfs)",
                 ["cli_fresh"], ["cli_tmpfs"]),
            part("replacing the files of the run before in one folder (cli - cli_fresh)",
                 ["cli"], ["cli_fresh"]),
            part("one knitsim process per drape (cli)", ["cli"]),
        ]
        sections.append((
            "Where a CLI call's time goes",
            "Per call, from the medians above (differences of sweeps run once each, so a row "
            "may be off by the machine's noise). The ratio CLI / Python is the sum of these "
            "over the warm call: a cheaper CLI lowers it; only a cheaper drape raises it.\n\n"
            + md_table(["part", "wall (ms)", "CPU (ms)"], parts)))
    sections.append(("Provenance", provenance(read_json(out, "manifest.json"))))
    return "The Python module: overhead and threads", ["runs.csv", "manifest.json"], sections


if __name__ == "__main__":
    summary_main("python", build)
