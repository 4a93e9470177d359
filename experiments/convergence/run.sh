#!/usr/bin/env bash
# Convergence study: driver.py writes the raw CSV and manifest.json into
# OUT, plot.py turns the CSV into PNGs. See README.md.
#
#   experiments/convergence/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/convergence. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" convergence orders.csv "$@"
