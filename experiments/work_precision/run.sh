#!/usr/bin/env bash
# Work-precision study: driver.py writes the raw CSV and manifest.json into
# OUT, plot.py turns the CSV into PNGs. See README.md.
#
#   experiments/work_precision/run.sh [--quick] [--out DIR] [--keep-runs] [--wall-cap S]
#
# Default OUT: out/experiments/work_precision. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" work_precision runs.csv "$@"
