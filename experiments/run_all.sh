#!/usr/bin/env bash
# One entry point for every study (STYLE.md practice 10): runs each experiments/<name>/run.sh
# found (so a new study is picked up by adding its folder), each with --out OUT/<name> and
# --quick if given, prints a summary table and writes OUT/summary.md.
#
#   experiments/run_all.sh [--quick] [--only NAME[,NAME...]] [--out DIR] [--timeout S]
#
#   --quick     every study's small mode (seconds to a minute each; what CI runs)
#   --only      run only these studies (folder names under experiments/)
#   --out       output root (default out/experiments); study NAME writes into OUT/NAME
#   --timeout   wall-clock limit per study, s (default none); a study over it counts as failed
#
# Every run.sh must accept --quick and --out DIR and exit non-zero when its own checks fail.
# The knitsim binary is $KNITSIM (passed on to the studies), else build/knitsim.
# Exit status: 0 if every study exited 0, 1 otherwise.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
ARGS="$*"
QUICK=()
ONLY=""
OUT=$root/out/experiments
TIMEOUT=0
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) QUICK=(--quick) ;;
    --only) ONLY=${2:?--only needs a list}; shift ;;
    --out) OUT=${2:?--out needs a folder}; shift ;;
    --timeout) TIMEOUT=${2:?--timeout needs seconds}; shift ;;
    *) echo "usage: $0 [--quick] [--only NAME[,NAME...]] [--out DIR] [--timeout S]" >&2; exit 2 ;;
  esac
  shift
done
export KNITSIM=${KNITSIM:-$root/build/knitsim}
[ -x "$KNITSIM" ] || { echo "run_all: $KNITSIM not built (run ./run.sh --build-only)" >&2; exit 2; }

studies=()
for script in "$here"/*/run.sh; do
  [ -x "$script" ] || continue
  name=$(basename "$(dirname "$script")")
  if [ -n "$ONLY" ] && [[ ",$ONLY," != *",$name,"* ]]; then continue; fi
  studies+=("$name")
done
if [ -n "$ONLY" ]; then
  for want in ${ONLY//,/ }; do
    if [[ " ${studies[*]} " != *" $want "* ]]; then
      echo "run_all: no experiments/$want/run.sh" >&2
      exit 2
    fi
  done
fi
[ ${#studies[@]} -gt 0 ] || { echo "run_all: no study to run" >&2; exit 2; }

mkdir -p "$OUT"
mode=$([ ${#QUICK[@]} -gt 0 ] && echo quick || echo full)
rows=()
failed=0
for name in "${studies[@]}"; do
  dir=$OUT/$name
  mkdir -p "$dir"
  log=$dir/run_all.log
  echo "== $name ($mode) -> $dir" >&2
  start=$(date +%s%N)
  cpu_before=$(awk '{print $14 + $15 + $16 + $17}' /proc/$$/stat)  # children's CPU, ticks
  if [ "$TIMEOUT" != 0 ]; then
    timeout "$TIMEOUT" "$here/$name/run.sh" "${QUICK[@]}" --out "$dir" > "$log" 2>&1
  else
    "$here/$name/run.sh" "${QUICK[@]}" --out "$dir" > "$log" 2>&1
  fi
  rc=$?
  wall=$(( ($(date +%s%N) - start) / 1000000 ))  # ms
  cpu=$(awk -v b="$cpu_before" -v hz="$(getconf CLK_TCK)" \
    '{printf "%.1f", ($14 + $15 + $16 + $17 - b) / hz}' /proc/$$/stat)
  case $rc in
    0) status=ok ;;
    124) status="timeout (${TIMEOUT} s)" ;;
    *) status="FAILED (exit $rc)" ;;
  esac
  [ $rc = 0 ] || { failed=1; tail -n 5 "$log" | sed 's/^/   | /' >&2; }
  outputs=$(cd "$dir" && ls -- *.csv *.png 2>/dev/null | tr '\n' ' ')
  wall_s=$(awk -v w="$wall" 'BEGIN{printf "%.1f", w / 1000}')
  rows+=("| $name | $status | $wall_s | $cpu | $outputs|")
done

summary=$OUT/summary.md
header="| study | status | wall (s) | CPU (s) | outputs |"
{
  echo "# Experiments ($mode)"
  echo
  echo "Command: \`experiments/run_all.sh $ARGS\`, $(date -u +%Y-%m-%dT%H:%M:%SZ)," \
       "git $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)," \
       "knitsim $KNITSIM, load average $(cut -d' ' -f1-3 /proc/loadavg)."
  echo
  echo "$header"
  echo "|---|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "Each study's folder holds its log (run_all.log), CSV files, manifest.json and PNGs;"
  echo "experiments/<study>/README.md says what they mean."
} > "$summary"
column -t -s '|' <(printf '%s\n' "$header" "${rows[@]}") >&2 \
  || printf '%s\n' "${rows[@]}" >&2
echo "run_all: wrote $summary" >&2
exit $failed
