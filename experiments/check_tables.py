#!/usr/bin/env python3
"""Checks that every committed summary.md of the studies (and of paper_repro/knit) is what its
summary.py makes of the committed CSV files: regenerates each into a temporary folder and compares bytes; also checks
that the study's README links to its summary.md. Standard library only; no knitsim run.

    python3 experiments/check_tables.py

Exit 0 when all match; 1 with one line per drifted or missing file (regenerate with
experiments/tables.sh after changing a CSV file or a summary.py).
"""
import glob
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import expkit  # noqa: E402


def main():
    scripts = sorted(glob.glob(os.path.join(HERE, "*", "summary.py")))
    if not scripts:
        print("check_tables: no experiments/<study>/summary.py found")
        return 1
    # Paper 2's figures keep their tables the same way, beside their own results.
    scripts.append(os.path.join(expkit.ROOT, "paper_repro", "knit", "summary.py"))
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        for script in scripts:
            study = os.path.basename(os.path.dirname(script))
            folder = (os.path.join(os.path.dirname(script), "results") if "paper_repro" in script
                      else expkit.committed_dir(study))
            committed = os.path.join(folder, "summary.md")
            shown = os.path.relpath(committed, expkit.ROOT)
            fresh = os.path.join(tmp, study + ".md")
            p = subprocess.run([sys.executable, script, "--output", fresh],
                               capture_output=True, text=True)
            if p.returncode != 0:
                last = (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]
                failures.append("%s: summary.py failed: %s" % (shown, last))
                continue
            if not os.path.exists(committed):
                failures.append("%s: missing (run experiments/tables.sh %s)" % (shown, study))
                continue
            with open(committed, "rb") as a, open(fresh, "rb") as b:
                if a.read() != b.read():
                    failures.append("%s: differs from what summary.py makes of the committed CSV "
                                    "(run experiments/tables.sh %s)" % (shown, study))
                    continue
            readme = os.path.join(os.path.dirname(script), "README.md")
            link = os.path.relpath(committed, os.path.dirname(readme))
            if not os.path.exists(readme) or link not in open(readme).read():
                failures.append("%s: does not link %s" % (os.path.relpath(readme, expkit.ROOT),
                                                          link))
    for f in failures:
        print("check_tables: " + f)
    if failures:
        return 1
    print("check_tables: %d summaries match their CSV" % len(scripts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
