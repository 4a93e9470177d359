#!/usr/bin/env bash
# Convergence study: driver.py writes the raw CSV and manifest.json into
# OUT, plot.py turns the CSV into PNGs. Then material_mesh.py adds the material model's mesh
# dimension beside paper 1's (material_mesh.csv, material_mesh.md). See README.md.
#
#   experiments/convergence/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/convergence. The knitsim binary: $KNITSIM, else build/knitsim.
status=0
"$(dirname "$0")/../study.sh" convergence orders.csv "$@" || status=$?
/usr/bin/python3 "$(dirname "$0")/material_mesh.py" "$@" || status=$?
exit $status
