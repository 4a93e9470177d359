#!/usr/bin/env bash
# equilibrium study: driver.py writes the raw CSV and manifest.json into OUT, plot.py the PNG and
# summary.md. See README.md.
#
#   experiments/equilibrium/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/equilibrium. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(dirname "$0")/../study.sh" equilibrium cost.csv "$@"
