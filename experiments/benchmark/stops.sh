#!/usr/bin/env bash
# How often does a drape inside the fit's parameter box fail to stop at equilibrium? The
# fits (knitsim fit, knitsim repro) run thousands of drapes at rtol 1e-8 and count a run that
# ends at t_max as a failed evaluation, so this rate matters for Tables 4 and 6.
#
#   experiments/benchmark/stops.sh [--n N] [--seed S] [--scene four_corner|two_corner]
#                                  [--symmetry none|half|quarter|eighth] [--rtol R] [--out DIR]
#
# Draws N parameter sets uniformly from the ICA box (src/fit/drape_fit.hpp DrapeBounds: stiffness
# 500-1200 N/m, damping 10-20 N s/m, elongation limit 5-20 %, L0 4-6 cm, topology a/b/c) and
# an areal density from paper 1's three (27.6, 41.65, 58.26 g/m^2), Python's random.Random(S),
# and runs each (on the model.symmetry reduction given, default none) with rtol R (default 1e-8,
# the fits') as
#   cvode-bdf --newton-solver ldl, cvode-bdf --newton-solver cg-ldl (the default), static.
# Writes DIR/stops.csv (one row per run: status, steps, final residual, t_final, CPU) and
# DIR/summary.csv (per integrator: runs, equilibria, median CPU), DIR/manifest.json; prints the
# summary; then summary.py writes DIR/summary.md. About 1 s of CPU per parameter set on two_corner.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
KNITSIM=${KNITSIM:-$root/build/knitsim}
N=30
SEED=5
SCENE=two_corner
SYMMETRY=none
RTOL=1e-8
OUT=$root/out/stops
usage="usage: $0 [--n N] [--seed S] [--scene four_corner|two_corner] [--symmetry none|half|quarter|eighth] [--rtol R] [--out DIR]"
while [ $# -gt 0 ]; do
  case "$1" in
    --n) N=$2; shift ;;
    --seed) SEED=$2; shift ;;
    --scene) SCENE=$2; shift ;;
    --symmetry) SYMMETRY=$2; shift ;;
    --rtol) RTOL=$2; shift ;;
    --out) OUT=$2; shift ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
  shift
done
case "$SCENE" in four_corner|two_corner) ;; *) echo "$usage" >&2; exit 2 ;; esac
case "$SYMMETRY" in none|half|quarter|eighth) ;; *) echo "$usage" >&2; exit 2 ;; esac
[[ "$N" =~ ^[1-9][0-9]*$ ]] || { echo "stops: --n = $N: must be an integer >= 1" >&2; exit 2; }
[ -x "$KNITSIM" ] || { echo "stops: $KNITSIM not built (run ./run.sh --build-only)" >&2; exit 2; }
mkdir -p "$OUT/runs"
csv=$OUT/stops.csv
echo "set,integrator,newton_solver,areal_density,stiffness,damping,elongation_limit,natural_length,topology,status,steps,residual,t_final,cpu_seconds" > "$csv"

python3 - "$N" "$SEED" > "$OUT/params.txt" <<'PY'
import random, sys
rng = random.Random(int(sys.argv[2]))
for _ in range(int(sys.argv[1])):
    print(repr(rng.uniform(500, 1200)), repr(rng.uniform(10, 20)), repr(rng.uniform(5, 20)),
          repr(rng.uniform(0.04, 0.06)), "abc"[rng.randrange(3)], rng.choice([27.6, 41.65, 58.26]))
PY

i=0
while read -r k c e L t rho; do
  i=$((i + 1))
  for variant in "cvode-bdf ldl" "cvode-bdf cg-ldl" "static cg-ldl"; do
    read -r integ ns <<< "$variant"
    dir=$OUT/runs/$i-$integ-$ns
    rm -rf "$dir"
    "$KNITSIM" drape --scene "$SCENE" --integrator "$integ" --newton-solver "$ns" --rtol "$RTOL" \
      --set model.symmetry="$SYMMETRY" \
      --set fabric.areal_density="$rho" --set model.stiffness="$k" --set model.damping="$c" \
      --set model.elongation_limit="$e" --set model.natural_length="$L" \
      --set model.topology="$t" --quiet --out "$dir" > /dev/null 2>&1 || true
    python3 - "$dir/summary.json" "$i" "$integ" "$ns" "$rho" "$k" "$c" "$e" "$L" "$t" >> "$csv" <<'PY'
import json, sys
run, rest = sys.argv[1], sys.argv[2:]
try:
    s = json.load(open(run))
    cells = [s["status"], str(s["steps"]), repr(s["residual"]), repr(s["t_final"]),
             repr(s["cpu_seconds"])]
except (OSError, ValueError, KeyError):
    cells = ["no_summary", "", "", "", ""]
print(",".join(rest + cells))
PY
  done
done < "$OUT/params.txt"

python3 - "$csv" "$OUT/summary.csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
out = []
for key in sorted({(r["integrator"], r["newton_solver"]) for r in rows}):
    rs = [r for r in rows if (r["integrator"], r["newton_solver"]) == key]
    ok = [r for r in rs if r["status"] == "equilibrium"]
    cpu = [float(r["cpu_seconds"]) for r in rs if r["cpu_seconds"]]
    worst = max((float(r["residual"]) for r in rs if r["status"] != "equilibrium" and r["residual"]),
                default=float("nan"))
    out.append(dict(integrator=key[0], newton_solver=key[1], runs=len(rs), equilibrium=len(ok),
                    not_equilibrium=len(rs) - len(ok), worst_unsettled_residual=worst,
                    cpu_median=statistics.median(cpu) if cpu else float("nan")))
w = csv.DictWriter(open(sys.argv[2], "w", newline=""), fieldnames=list(out[0].keys()))
w.writeheader()
w.writerows(out)
for o in out:
    print(o)
PY

commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
python3 - "$OUT/manifest.json" "$KNITSIM" "$N" "$SEED" "$SCENE" "$commit" "$SYMMETRY" "$RTOL" <<'PY'
import json, sys, datetime, os
json.dump({"experiment": "benchmark/stops",
           "command": "experiments/benchmark/stops.sh --n %s --seed %s --scene %s --symmetry %s --rtol %s"
                      % (tuple(sys.argv[3:6]) + tuple(sys.argv[7:9])),
           "knitsim": sys.argv[2], "git_commit": sys.argv[6],
           "created_utc": datetime.datetime.utcnow().isoformat() + "Z",
           "load_average": os.getloadavg(), "nproc": os.cpu_count()},
          open(sys.argv[1], "w"), indent=2)
PY
echo "stops: wrote $csv, $OUT/summary.csv, $OUT/manifest.json"
python3 "$here/summary.py" "$OUT"  # summary.md: the tables of README.md, from the CSV files
