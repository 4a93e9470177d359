#!/usr/bin/env bash
# knit_relaxed study: driver.py relaxes plain jersey as a periodic yarn cell (knitsim knit
# --set knit.model=yarn --set knit.boundary=periodic) at tightness factors 1.47 and 1.3, over
# stitch lengths +-20 % and edge lengths halved, and writes runs.csv and manifest.json into OUT;
# summary.py writes the tables (summary.md). See README.md.
#
#   experiments/knit_relaxed/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/knit_relaxed. The knitsim binary: $KNITSIM, else build/knitsim.
exec "$(cd "$(dirname "$0")" && pwd)/../study.sh" knit_relaxed runs.csv "$@"
