"""Checks the outputs of knitsim_optimizers (the counting wrapper's invariants); exit 1 if any
fails. Standard library only.

    check.py OUT                 check runs.csv, trace.csv and manifest.json in OUT
    check.py --run BINARY OUT    first run BINARY with a tiny budget (12 evaluations, 1 seed,
                                 every optimizer) into OUT -- the ctest optimizers_budget

Invariants, per (optimizer, seed):
  * evaluations <= budget; a population method (not lm) spent exactly `budget` (stop =
    budget: the wrapper ended it; finished: its generations ended there); lm stops by itself or
    by the budget (then exactly `budget`);
  * trace rows: the first evaluation is 1, evaluations strictly increase, the last row is
    evaluation `evaluations`; best_so_far never rises (rows are the improvements, written with
    8 digits, so the smallest ones repeat a value); cpu_seconds never decreases;
  * final_error equals the last best_so_far;
  * every optimizer of the manifest ran every seed 1..seeds.
"""
import csv
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def check(out):
    import json
    manifest = json.load(open(os.path.join(out, "manifest.json")))
    options = manifest["options"]
    budget, seeds = options["budget"], options["seeds"]
    runs = list(csv.DictReader(open(os.path.join(out, "runs.csv"))))
    trace = {}
    for r in csv.DictReader(open(os.path.join(out, "trace.csv"))):
        trace.setdefault((r["optimizer"], int(r["seed"])), []).append(r)
    problems = []

    def bad(key, what):
        problems.append("%s seed %d: %s" % (key[0], key[1], what))

    seen = set()
    for r in runs:
        key = (r["optimizer"], int(r["seed"]))
        seen.add(key)
        n = int(r["evaluations"])
        if n > budget:
            bad(key, "%d evaluations > budget %d" % (n, budget))
        if r["stop"] == "budget" and n != budget:
            bad(key, "stopped by the budget after %d evaluations, budget %d" % (n, budget))
        if key[0] != "lm" and n != budget:
            bad(key, "a population method spent %d evaluations, budget %d" % (n, budget))
        t = trace.get(key, [])
        if not t:
            bad(key, "no trace")
            continue
        evals = [int(p["evaluation"]) for p in t]
        best = [float(p["best_so_far"]) for p in t]
        cpu = [float(p["cpu_seconds"]) for p in t]
        if evals[0] != 1 or evals[-1] != n:
            bad(key, "trace spans evaluations %d..%d, expected 1..%d" % (evals[0], evals[-1], n))
        if any(b <= a for a, b in zip(evals, evals[1:])):
            bad(key, "trace evaluations not increasing")
        if any(b > a for a, b in zip(best, best[1:])):
            bad(key, "best_so_far rises: %s" % best)
        if any(b < a for a, b in zip(cpu, cpu[1:])):
            bad(key, "cpu_seconds decreasing")
        if float(r["final_error"]) != best[-1]:
            bad(key, "final_error %s != last best_so_far %s" % (r["final_error"], best[-1]))
    for name in options["optimizers"]:
        for s in range(1, seeds + 1):
            if (name, s) not in seen:
                problems.append("%s seed %d: missing from runs.csv" % (name, s))
    for p in problems:
        print("check: " + p, file=sys.stderr)
    print("check: %d runs, %d problems" % (len(runs), len(problems)))
    return not problems


def main(argv):
    if len(argv) == 3 and argv[0] == "--run":
        binary, out = argv[1], argv[2]
        subprocess.run([binary, "--budget", "12", "--seeds", "1", "--out", out, "--target",
                        os.path.join(ROOT, "paper_repro/data/targets/twin_sample1.csv")],
                       check=True)
    elif len(argv) == 1:
        out = argv[0]
    else:
        sys.exit("usage: check.py [--run BINARY] OUT")
    return 0 if check(out) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
