#!/usr/bin/env bash
# tensile study: driver.py writes three 24 x 24 charts (plain jersey, a tuck and a miss pattern),
# pulls each along the wales and the courses with knitsim tensile (loading and unloading) and
# writes curves.csv, runs.csv and manifest.json into OUT; plot.py draws tensile.png and runs
# summary.py (summary.md). See README.md.
#
#   experiments/tensile/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/tensile. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(cd "$(dirname "$0")" && pwd)/../study.sh" tensile curves.csv "$@"
