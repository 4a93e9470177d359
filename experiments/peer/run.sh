#!/usr/bin/env bash
# peer study: driver.py writes the raw CSV and manifest.json into OUT, plot.py turns the CSV
# into PNGs. See README.md.
#
#   experiments/peer/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/peer. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" peer compare.csv "$@"
