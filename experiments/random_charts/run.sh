#!/usr/bin/env bash
# random_charts study: driver.py writes the seeded charts, runs knitsim knit on each and writes
# random_charts.csv and manifest.json into OUT; summary.py then writes OUT/summary.md. No plot.
# See README.md.
#
#   experiments/random_charts/run.sh [--quick] [--out DIR] [--count N] [--seed S]
#       [--require-clearance X] [--keep-runs] [-- extra knitsim knit arguments]
#
# Default OUT: out/experiments/random_charts. The knitsim binary: $KNITSIM, else build/knitsim.
# Exit status: the driver's (1 if a run was refused or crashed, or a --require-clearance check
# failed; everything is written first).
exec "$(cd "$(dirname "$0")" && pwd)/../study.sh" random_charts random_charts.csv "$@"
