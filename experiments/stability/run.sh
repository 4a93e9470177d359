#!/usr/bin/env bash
# stability study: driver.py writes the raw CSV and manifest.json into OUT, plot.py turns the CSV
# into PNGs. See README.md.
#
#   experiments/stability/run.sh [--quick] [--out DIR] [--keep-runs]
#
# Default OUT: out/experiments/stability. The knitsim binary: $KNITSIM, else build/knitsim.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=$(cd "$here/../.." && pwd)/out/experiments/stability
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  [ "${args[i]}" = "--out" ] && out=${args[i + 1]:-$out}
done
status=0
/usr/bin/python3 "$here/driver.py" "$@" || status=$?
[ -f "$out/limits.csv" ] && /usr/bin/python3 "$here/plot.py" "$out"
exit $status
