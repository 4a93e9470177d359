#!/usr/bin/env bash
# Convergence study (issue 5 item 2): driver.py writes the raw CSV and manifest.json into
# OUT, plot.py turns the CSV into PNGs. See README.md.
#
#   experiments/convergence/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/convergence. The knitsim binary: $KNITSIM, else build/knitsim.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=$(cd "$here/../.." && pwd)/out/experiments/convergence
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  [ "${args[i]}" = "--out" ] && out=${args[i + 1]:-$out}
done
status=0
/usr/bin/python3 "$here/driver.py" "$@" || status=$?
[ -f "$out/orders.csv" ] && /usr/bin/python3 "$here/plot.py" "$out"
exit $status
