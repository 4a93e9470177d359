#!/usr/bin/env bash
# reductions study: driver.py writes the raw CSV and manifest.json into OUT, plot.py turns the CSV
# into PNGs. See README.md.
#
#   experiments/reductions/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/reductions. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" reductions stop.csv "$@"
