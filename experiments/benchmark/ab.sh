#!/usr/bin/env bash
# Is build B faster than build A on one knitsim command? Two binaries run the same command in
# alternation (A, B, A, B, ...), so a drift in the machine's load or speed hits both alike; the
# solver CPU of each run is summary.json's cpu_seconds (set-up and file output excluded).
#
#   experiments/benchmark/ab.sh [--pairs N] [--out DIR] A B -- drape|knit ARGS...
#
# Prints the median CPU of each binary, their ratio B / A and the number of pairs (default 9);
# --no-pictures and --quiet are added to every run. DIR (default out/ab) keeps the last run of
# each. Example (two binaries of two commits, built beforehand):
#   experiments/benchmark/ab.sh --pairs 15 /tmp/knitsim-b405e40 /tmp/knitsim-e57b76b -- \
#     drape --scene four_corner
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
PAIRS=9
OUT=$root/out/ab
usage="usage: $0 [--pairs N] [--out DIR] A B -- drape|knit ARGS..."
while [ $# -gt 0 ]; do
  case "$1" in
    --pairs) PAIRS=${2:-}; shift ;;
    --out) OUT=${2:-}; shift ;;
    --) echo "$usage" >&2; exit 2 ;;
    -*) echo "$usage" >&2; exit 2 ;;
    *) break ;;
  esac
  shift
done
[ $# -ge 4 ] && [ "$3" = "--" ] || { echo "$usage" >&2; exit 2; }
A=$1 B=$2
shift 3
[[ "$PAIRS" =~ ^[1-9][0-9]*$ ]] || { echo "ab: --pairs = $PAIRS: must be an integer >= 1" >&2; exit 2; }
for bin in "$A" "$B"; do
  [ -x "$bin" ] || { echo "ab: $bin is not an executable knitsim" >&2; exit 2; }
done
mkdir -p "$OUT"
times=$OUT/cpu_seconds.txt
: > "$times"
for _ in $(seq "$PAIRS"); do
  for side in A B; do
    bin=$A
    [ "$side" = B ] && bin=$B
    rm -rf "${OUT:?}/$side"
    rc=0
    "$bin" "$@" --no-pictures --quiet --out "$OUT/$side" > /dev/null 2> "$OUT/$side.stderr" || rc=$?
    if [ "$rc" != 0 ] && [ "$rc" != 3 ]; then
      echo "ab: $side ($bin) exited $rc:" >&2
      cat "$OUT/$side.stderr" >&2
      exit 1
    fi
    /usr/bin/python3 -c 'import json, sys
d = json.load(open(sys.argv[1]))
print(sys.argv[2], d.get("stats", d)["cpu_seconds"])' "$OUT/$side/summary.json" "$side" >> "$times"
  done
done
/usr/bin/python3 - "$times" "$A" "$B" <<'PY'
import statistics, sys
runs = {"A": [], "B": []}
for line in open(sys.argv[1]):
    side, cpu = line.split()
    runs[side].append(float(cpu))
a, b = statistics.median(runs["A"]), statistics.median(runs["B"])
print("A %s: median CPU %.4g s" % (sys.argv[2], a))
print("B %s: median CPU %.4g s" % (sys.argv[3], b))
print("B / A = %.3f over %d pairs" % (b / a, len(runs["A"])))
PY
