#!/usr/bin/env bash
# What does one `knitsim drape` / `knitsim knit` call cost from the shell, and how much of it is
# the pictures? For scripts that loop over the CLI (parameter sweeps), where process start,
# output writing and PNG rendering add to the solve that summary.json's cpu_seconds reports.
#
#   experiments/benchmark/cli_cost.sh [--n N] [--out DIR]
#
# Runs each case N times (default 11) with and without --no-pictures, alternating, and prints
# the median wall time of each (Python's perf_counter around the process, start to exit) and
# their ratio; DIR (default out/cli_cost) receives the runs' output folders. Cases: drape
# four_corner, drape two_corner, knit models/charts/single_tuck.chart (4 frames). ~15 s.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
KNITSIM=${KNITSIM:-$root/build/knitsim}
N=11
OUT=$root/out/cli_cost
usage="usage: $0 [--n N] [--out DIR]"
while [ $# -gt 0 ]; do
  case "$1" in
    --n) N=$2; shift ;;
    --out) OUT=$2; shift ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
  shift
done
[[ "$N" =~ ^[1-9][0-9]*$ ]] || { echo "cli_cost: --n = $N: must be an integer >= 1" >&2; exit 2; }
[ -x "$KNITSIM" ] || { echo "cli_cost: $KNITSIM not built (run ./run.sh --build-only)" >&2; exit 2; }
rm -rf "$OUT"
mkdir -p "$OUT"
/usr/bin/python3 - "$KNITSIM" "$N" "$OUT" "$root/models/charts/single_tuck.chart" <<'PY'
import statistics, subprocess, sys, time
exe, n, out, chart = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
cases = {"drape four_corner": ["drape", "--quiet"],
         "drape two_corner": ["drape", "--scene", "two_corner", "--quiet"],
         "knit single_tuck": ["knit", "--chart", chart, "--set", "knit.contact=0", "--quiet"]}
print("case,median_wall_ms_pictures,median_wall_ms_no_pictures,ratio")
for name, args in cases.items():
    wall = {"pictures": [], "no_pictures": []}
    for i in range(n):
        for mode in wall:
            cmd = [exe] + args + ["--out", f"{out}/{name.replace(' ', '_')}-{mode}-{i}"]
            if mode == "no_pictures":
                cmd.append("--no-pictures")
            start = time.perf_counter()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            wall[mode].append(time.perf_counter() - start)
    a, b = statistics.median(wall["pictures"]), statistics.median(wall["no_pictures"])
    print(f"{name},{1e3 * a:.1f},{1e3 * b:.1f},{a / b:.2f}")
PY
