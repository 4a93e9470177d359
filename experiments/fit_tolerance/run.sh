#!/usr/bin/env bash
# fit_tolerance study: driver.py writes the raw CSV and manifest.json into OUT, plot.py turns the CSV
# into PNGs. See README.md.
#
#   experiments/fit_tolerance/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/fit_tolerance. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" fit_tolerance fits.csv "$@"
