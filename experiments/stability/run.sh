#!/usr/bin/env bash
# stability study: driver.py writes the raw CSV and manifest.json into OUT, plot.py turns the CSV
# into PNGs. See README.md.
#
#   experiments/stability/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/stability. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" stability limits.csv "$@"
