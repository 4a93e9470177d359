#!/usr/bin/env bash
# transient study: driver.py writes the raw CSV and manifest.json into OUT, plot.py turns the CSV
# into PNGs and runs summary.py. See README.md.
#
#   experiments/transient/run.sh [--quick] [--out DIR] [--keep-runs] [--wall-cap S]
#
# Default OUT: out/experiments/transient. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" transient runs.csv "$@"
