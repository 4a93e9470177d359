#!/usr/bin/env bash
# The run.sh of a Python study (STYLE.md practice 10): driver.py writes the raw CSV and
# manifest.json into OUT, then plot.py turns the CSV into PNGs (a study without plots: summary.py
# writes its tables) if the driver got that far. Arguments after "--" are the driver's to pass on.
#
#   experiments/study.sh NAME CSV [driver arguments: --quick --out DIR ...]
#
# NAME is the study's folder under experiments/, CSV the file whose presence means there is
# something to plot. Default OUT: out/experiments/NAME. Exit status: the driver's.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
name=$1 csv=$2
shift 2
here=$root/experiments/$name
out=$root/out/experiments/$name
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  [ "${args[i]}" = "--" ] && break
  [ "${args[i]}" = "--out" ] && out=${args[i + 1]:-$out}
done
status=0
/usr/bin/python3 "$here/driver.py" "$@" || status=$?
after=$here/plot.py
[ -f "$after" ] || after=$here/summary.py
[ -f "$out/$csv" ] && /usr/bin/python3 "$after" "$out"
exit $status
