#!/usr/bin/env bash
# Optimizers side by side (README.md): knitsim_optimizers writes runs.csv, trace.csv,
# reference.csv and manifest.json into OUT, check.py checks the counting wrapper's invariants,
# plot.py writes the PNGs and the summary table.
#
#   experiments/optimizers/run.sh [--quick] [--out DIR] [--budget B] [--seeds S]
#
#   --quick  2 seeds x 40 drapes per optimizer (~30 s CPU); default 10 seeds x 300 drapes
#            (~25 min CPU)
# Default OUT: out/experiments/optimizers. The driver: $KNITSIM_OPTIMIZERS, else
# knitsim_optimizers next to $KNITSIM, else build/knitsim_optimizers (built when pagmo2, Debian
# libpagmo-dev, is installed: ./run.sh installs it).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
here=$root/experiments/optimizers
out=$root/out/experiments/optimizers
budget=300 seeds=10
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) budget=40 seeds=2 ;;
    --out) out=${2:?--out needs a folder}; shift ;;
    --budget) budget=${2:?}; shift ;;
    --seeds) seeds=${2:?}; shift ;;
    *) echo "usage: $0 [--quick] [--out DIR] [--budget B] [--seeds S]" >&2; exit 2 ;;
  esac
  shift
done
if [ -z "${KNITSIM_OPTIMIZERS:-}" ]; then
  KNITSIM_OPTIMIZERS=$root/build/knitsim_optimizers
  [ -n "${KNITSIM:-}" ] && KNITSIM_OPTIMIZERS=$(dirname "$KNITSIM")/knitsim_optimizers
fi
if [ ! -x "$KNITSIM_OPTIMIZERS" ]; then
  echo "optimizers: $KNITSIM_OPTIMIZERS not built (needs pagmo2: apt-get install libpagmo-dev," \
       "then rebuild)" >&2
  exit 2
fi
mkdir -p "$out"
"$KNITSIM_OPTIMIZERS" --budget "$budget" --seeds "$seeds" --out "$out" \
  --target "$root/paper_repro/data/targets/twin_sample1.csv"
status=0
/usr/bin/python3 "$here/check.py" "$out" || status=1
/usr/bin/python3 "$here/plot.py" "$out" || status=1
exit $status
