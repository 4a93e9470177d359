#!/usr/bin/env bash
# Knit benchmark, absolute tolerances (target: a 40 x 40 chart with tucks to steady state
# with cvode-bdf in <= 1 s). models/charts/tucks40.chart (23 single tucks) with the
# stabiliser at 0.1 and no yarn contact: cvode-bdf over velocity_atol x atol x rtol against a
# tight reference, verlet at its automatic stable step for comparison, then what velocity_atol
# does to the two drape scenes at the fit's rtol 1e-8.
#
#   experiments/benchmark/knit_atol.sh [--part all|sweep|timed|drape] [--repeats N] [--out DIR]
#
#   reference: implicit-euler (dt 1 s) to residual 1e-10 (it lands at 2.4e-12 in 5 steps);
#   sweep:     rtol {1e-6, 1e-4} x atol {1e-9, 1e-8, 1e-7} x velocity_atol {0, 1e-9 .. 1e-1}
#              (0 = atol on the velocities too), one run each;
#   timed:     cvode-bdf at the knit defaults (Newton solver cg-ldl, and ldl for the ratio), at
#              the drape defaults (rtol 1e-6, atol 1e-9, velocity_atol 0) and verlet, N runs
#              each, interleaved (CPU medians in knit_timed.csv);
#   drape:     four_corner and two_corner, cvode-bdf, rtol 1e-8, atol 1e-9, velocity_atol
#              {0, 1e-8, 1e-6, 1e-4, 1e-2}: steps, set-ups, CPU, and the largest relative change
#              of an edge's coefficient vector |c - c0| / |c0| against velocity_atol 0.
# Knit rows (knit_row.py): status, steps, set-ups, Newton iterations, CPU (summary.json stats),
# final residual, and the largest point distance from the reference in loop radii, as written
# (dx_max_over_r) and after the best rigid motion (shape_dx_over_r; the free network's steady
# state is unique only up to one). Writes DIR/knit.csv, DIR/knit_timed.csv, DIR/drape.csv,
# DIR/manifest.json (a part replaces its own rows), then DIR/summary.md (summary.py). About 15
# minutes of CPU for all parts.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
KNITSIM=${KNITSIM:-$root/build/knitsim}
REPEATS=3
PART=all
OUT=$root/out/knit_atol
usage="usage: $0 [--part all|sweep|timed|drape] [--repeats N] [--out DIR]"
while [ $# -gt 0 ]; do
  case "$1" in
    --part) PART=$2; shift ;;
    --repeats) REPEATS=$2; shift ;;
    --out) OUT=$2; shift ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
  shift
done
case "$PART" in all|sweep|timed|drape) ;; *) echo "$usage" >&2; exit 2 ;; esac
part() { [ "$PART" = all ] || [ "$PART" = "$1" ]; }
[ -x "$KNITSIM" ] || { echo "knit_atol: $KNITSIM not built (run ./run.sh --build-only)" >&2; exit 2; }
CHART=$root/models/charts/tucks40.chart
mkdir -p "$OUT/runs"
knit_csv=$OUT/knit.csv
header=$(python3 "$here/knit_row.py" --header)
if [ -f "$knit_csv" ] && [ "$(head -n 1 "$knit_csv")" != "$header" ]; then
  mv "$knit_csv" "$knit_csv.old"  # written by an older knit_row.py: other columns
  echo "knit_atol: $knit_csv had other columns; moved to $knit_csv.old" >&2
fi
[ -f "$knit_csv" ] || echo "$header" > "$knit_csv"

# knit CASE INTEGRATOR REPEAT ARGS...: one knitsim knit run into runs/CASE-REPEAT; replaces its
# knit.csv row (distances against runs/reference-1, none for the reference itself).
knit() {
  local case=$1 integ=$2 rep=$3; shift 3
  local dir=$OUT/runs/$case-$rep
  rm -rf "$dir"
  "$KNITSIM" knit --chart "$CHART" --set knit.stabiliser=0.1 --set knit.contact=0 \
    --integrator "$integ" --quiet \
    --frames 1 --out "$dir" "$@" || true
  grep -v "^$case,[^,]*,[^,]*,[^,]*,[^,]*,$rep," "$knit_csv" > "$knit_csv.tmp" || true
  python3 "$here/knit_row.py" "$dir" "$OUT/runs/reference-1" "$case" "$rep" >> "$knit_csv.tmp"
  mv "$knit_csv.tmp" "$knit_csv"
  tail -n 1 "$knit_csv"
}

if part sweep || part timed; then
  knit reference implicit-euler 1 --set run.equilibrium_tol=1e-10
fi
if part sweep; then
  for rtol in 1e-6 1e-4; do
    for atol in 1e-9 1e-8 1e-7; do
      for vatol in 0 1e-9 1e-8 1e-7 1e-6 1e-5 1e-4 1e-3 1e-2 1e-1; do
        knit "sweep-r$rtol-a$atol-v$vatol" cvode-bdf 1 --rtol "$rtol" --atol "$atol" \
          --velocity-atol "$vatol"
      done
    done
  done
fi
if part timed; then
  for rep in $(seq 1 "$REPEATS"); do
    knit knit-defaults cvode-bdf "$rep"
    knit knit-defaults-ldl cvode-bdf "$rep" --newton-solver ldl
    knit drape-defaults cvode-bdf "$rep" --rtol 1e-6 --atol 1e-9 --velocity-atol 0
    knit verlet verlet "$rep"
  done
  python3 - "$knit_csv" "$OUT/knit_timed.csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
out = []
for case in ["knit-defaults", "knit-defaults-ldl", "drape-defaults", "verlet"]:
    rs = [r for r in rows if r["case"] == case]
    cpu = sorted(float(r["cpu_seconds"]) for r in rs)
    out.append(dict(case=case, integrator=rs[0]["integrator"], rtol=rs[0]["rtol"],
                    atol=rs[0]["atol"], velocity_atol=rs[0]["velocity_atol"], runs=len(rs),
                    newton_solver=rs[0]["newton_solver"], status=rs[0]["status"],
                    steps=rs[0]["steps"], lin_setups=rs[0]["lin_setups"],
                    factorisations=rs[0]["factorisations"],
                    cpu_median=statistics.median(cpu), cpu_min=cpu[0], cpu_max=cpu[-1],
                    shape_dx_over_r=rs[0]["shape_dx_over_r"]))
w = csv.DictWriter(open(sys.argv[2], "w", newline=""), fieldnames=list(out[0].keys()))
w.writeheader(); w.writerows(out)
for o in out: print(o)
PY
fi

drape_csv=$OUT/drape.csv
if part drape; then
  echo "scene,velocity_atol,status,steps,lin_setups,cpu_seconds,residual,max_edge_relative_change" > "$drape_csv"
  for scene in four_corner two_corner; do
    for vatol in 0 1e-8 1e-6 1e-4 1e-2; do
      dir=$OUT/runs/drape-$scene-v$vatol
      rm -rf "$dir"
      "$KNITSIM" drape --scene "$scene" --integrator cvode-bdf --rtol 1e-8 --atol 1e-9 \
        --velocity-atol "$vatol" --quiet --out "$dir" >/dev/null || true
      python3 - "$dir" "$OUT/runs/drape-$scene-v0" "$scene" >> "$drape_csv" <<'PY'
import json, sys
s = json.load(open(sys.argv[1] + "/summary.json"))
ref = json.load(open(sys.argv[2] + "/summary.json"))
# per edge: |c - c_ref| / |c_ref| over its polynomial's coefficient vector; the largest edge
a, b = s.get("edge_coefficients", {}), ref.get("edge_coefficients", {})
def norm(v): return sum(x * x for x in v) ** 0.5
change = max((norm([x - y for x, y in zip(a[e], b[e])]) / norm(b[e]) for e in b if e in a),
             default=float("nan"))
print(",".join([sys.argv[3], repr(s["options"]["velocity_atol"]), s["status"], str(s["steps"]),
                str(s["lin_setups"]), repr(s["cpu_seconds"]), repr(s["residual"]),
                repr(change)]))
PY
      tail -n 1 "$drape_csv"
    done
  done
fi

commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
python3 - "$OUT/manifest.json" "$KNITSIM" "$REPEATS" "$commit" "$PART" <<'PY'
import json, sys, datetime, os
json.dump({"experiment": "benchmark/knit_atol", "command": "experiments/benchmark/knit_atol.sh --part " + sys.argv[5],
           "chart": "models/charts/tucks40.chart", "repeats": int(sys.argv[3]),
           "knitsim": sys.argv[2], "git_commit": sys.argv[4],
           "created_utc": datetime.datetime.utcnow().isoformat() + "Z",
           "load_average": os.getloadavg(), "nproc": os.cpu_count()},
          open(sys.argv[1], "w"), indent=2)
PY
echo "knit_atol: wrote $OUT/knit.csv, $OUT/knit_timed.csv, $OUT/drape.csv, $OUT/manifest.json"
python3 "$here/summary.py" "$OUT"  # summary.md: the tables of README.md, from the CSV files
