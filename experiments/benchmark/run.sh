#!/usr/bin/env bash
# Drape benchmark (experiments/benchmark/README.md): cvode-bdf on four_corner and two_corner as
# medians of REPEATS runs, on the whole sheet and on the part each scene requires (the eighth
# of four_corner, the half of two_corner: model.symmetry), and the paper's explicit Euler reference on four_corner to the
# same residual (the benchmark fabric: k 852 N/m, c 12 N s/m, L0 4.9 cm, 41.65 g/m^2, topology a,
# i.e. the built-in scenes' defaults).
#
#   experiments/benchmark/run.sh [--quick] [--repeats N] [--out DIR]
#
# Euler runs at 0.9 x its predicted stability limit (the largest step it can take). In full
# mode it runs to equilibrium (about 5-10 minutes); with --quick it runs EULER_QUICK_STEPS steps
# and its cost to equilibrium is extrapolated from the measured time per step and the
# physical settling time t_settle measured by verlet (second order, same ODE).
# Writes DIR/runs.csv (every run), DIR/summary.csv (medians), DIR/manifest.json; prints a table;
# then summary.py writes DIR/summary.md (the tables of README.md).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
KNITSIM=${KNITSIM:-$root/build/knitsim}
REPEATS=5
QUICK=0
OUT=$root/out/benchmark
EULER_QUICK_STEPS=2000000
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) QUICK=1 ;;
    --repeats) REPEATS=$2; shift ;;
    --out) OUT=$2; shift ;;
    *) echo "usage: $0 [--quick] [--repeats N] [--out DIR]" >&2; exit 2 ;;
  esac
  shift
done
[ -x "$KNITSIM" ] || { echo "benchmark: $KNITSIM not built (run ./run.sh --build-only)" >&2; exit 2; }
mkdir -p "$OUT/runs"
runs_csv=$OUT/runs.csv
echo "scene,integrator,repeat,status,t_final,steps,rhs_evals,jac_evals,lin_setups,residual,dt,wall_seconds,cpu_seconds" > "$runs_csv"

# One drape; appends a row to runs.csv. Extra arguments go to knitsim drape.
drape() {
  local scene=$1 integ=$2 rep=$3; shift 3
  local dir=$OUT/runs/$scene-$integ-$rep
  rm -rf "$dir"
  # The whole sheet unless the caller names a reduction (a key may be given once).
  local whole=(--set model.symmetry=none)
  case " $* " in *model.symmetry=*) whole=() ;; esac
  "$KNITSIM" drape --scene "$scene" --integrator "$integ" --quiet --out "$dir" \
    "${whole[@]}" "$@" >/dev/null || true
  python3 - "$dir/summary.json" "$scene" "$integ" "$rep" >> "$runs_csv" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(",".join([sys.argv[2], sys.argv[3], sys.argv[4], s["status"], repr(s["t_final"]),
                str(s["steps"]), str(s["rhs_evals"]), str(s["jac_evals"]), str(s["lin_setups"]),
                repr(s["residual"]), repr(s["dt"]), repr(s["wall_seconds"]),
                repr(s["cpu_seconds"])]))
PY
}

for scene in four_corner two_corner; do
  for rep in $(seq 1 "$REPEATS"); do drape "$scene" cvode-bdf "$rep"; done
done
# The same drapes on the part of the sheet each scene requires (experiments/reductions: the
# same equilibrium to 2.4e-11 m and 7.2e-10 m); rows labelled scene/symmetry.
for rep in $(seq 1 "$REPEATS"); do
  drape four_corner cvode-bdf "eighth$rep" --set model.symmetry=eighth
  drape two_corner cvode-bdf "half$rep" --set model.symmetry=half
done
# The cheapest settled four_corner run of the work-precision study: implicit-euler at a fixed
# dt of 100 s (a step chosen from that study, not automatic; on two_corner a large fixed step
# lands on another equilibrium, experiments/work_precision). Row four_corner/dt100s.
for rep in $(seq 1 "$REPEATS"); do
  drape four_corner implicit-euler "dt100s$rep" --dt 100
done

# Euler: its predicted stability limit from a one-step run, then 0.9 x that step.
drape four_corner euler probe --max-steps 1
dt_pred=$(python3 -c "import json;print(json.load(open('$OUT/runs/four_corner-euler-probe/summary.json'))['dt_predicted'])")
dt_euler=$(python3 -c "print(0.9*$dt_pred)")
if [ "$QUICK" = 1 ]; then
  drape four_corner euler 1 --dt "$dt_euler" --max-steps "$EULER_QUICK_STEPS"
  drape four_corner verlet settle
else
  drape four_corner euler 1 --dt "$dt_euler"
fi

python3 - "$runs_csv" "$OUT/summary.csv" "$QUICK" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
quick = sys.argv[3] == "1"
out = []
def med(rs, k): return statistics.median(float(r[k]) for r in rs)
for scene, integ, part in [("four_corner", "cvode-bdf", ""), ("two_corner", "cvode-bdf", ""),
                           ("four_corner", "cvode-bdf", "eighth"),
                           ("two_corner", "cvode-bdf", "half"),
                           ("four_corner", "implicit-euler", "dt100s")]:
    rs = [r for r in rows if r["scene"] == scene and r["integrator"] == integ and
          r["repeat"].rstrip("0123456789") == part]
    out.append(dict(scene=scene + ("/" + part if part else ""), integrator=integ, runs=len(rs),
                    status="/".join(sorted(set(r["status"] for r in rs))),
                    t_final=med(rs, "t_final"), steps=med(rs, "steps"),
                    wall_seconds=med(rs, "wall_seconds"), cpu_seconds=med(rs, "cpu_seconds"),
                    measured="yes"))
eu = [r for r in rows if r["integrator"] == "euler" and r["repeat"] == "1"][0]
per_step = float(eu["wall_seconds"]) / float(eu["steps"])
per_step_cpu = float(eu["cpu_seconds"]) / float(eu["steps"])
if quick:
    settle = [r for r in rows if r["integrator"] == "verlet"][0]
    t_settle = float(settle["t_final"])
    steps = t_settle / float(eu["dt"])
    out.append(dict(scene="four_corner", integrator="euler", runs=1, status="extrapolated",
                    t_final=t_settle, steps=steps, wall_seconds=steps * per_step,
                    cpu_seconds=steps * per_step_cpu,
                    measured="no: %s steps timed, t_settle from verlet" % eu["steps"]))
else:
    out.append(dict(scene="four_corner", integrator="euler", runs=1, status=eu["status"],
                    t_final=float(eu["t_final"]), steps=float(eu["steps"]),
                    wall_seconds=float(eu["wall_seconds"]), cpu_seconds=float(eu["cpu_seconds"]),
                    measured="yes"))
euler_row = out[-1]
# The fixed-step run's equilibrium against cvode-bdf's: largest node distance, m.
import os
def nodes(label):
    path = os.path.join(os.path.dirname(sys.argv[1]), "runs", label, "nodes.csv")
    return [(float(r["x"]), float(r["y"]), float(r["z"])) for r in csv.DictReader(open(path))]
dx = max(max(abs(a - b) for a, b in zip(p, q)) for p, q in
         zip(nodes("four_corner-implicit-euler-dt100s1"), nodes("four_corner-cvode-bdf-1")))
w = csv.DictWriter(open(sys.argv[2], "w", newline=""), fieldnames=list(out[0].keys()))
w.writeheader(); w.writerows(out)
print("%-18s %-14s %4s %-13s %11s %11s %10s %10s  %s" % ("scene", "integrator", "runs",
      "status", "t_final s", "steps", "wall s", "cpu s", "measured"))
for o in out:
    print("%-18s %-14s %4d %-13s %11.4g %11.4g %10.4g %10.4g  %s" % (o["scene"], o["integrator"],
          o["runs"], o["status"], o["t_final"], o["steps"], o["wall_seconds"], o["cpu_seconds"],
          o["measured"]))
print("euler / cvode-bdf on four_corner, same residual: wall %.3g, cpu %.3g" % (
      euler_row["wall_seconds"] / out[0]["wall_seconds"],
      euler_row["cpu_seconds"] / out[0]["cpu_seconds"]))
print("euler time per step: %.3g us wall, %.3g us cpu (dt = %s s)" % (per_step * 1e6,
      per_step_cpu * 1e6, eu["dt"]))
print("four_corner implicit-euler dt 100 s vs cvode-bdf: equilibria %.2g m apart (largest node "
      "distance)" % dx)
PY
commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
python3 - "$OUT/manifest.json" "$KNITSIM" "$QUICK" "$REPEATS" "$commit" <<'PY'
import json, sys, datetime, os
commit = sys.argv[5]
m = {"experiment": "benchmark",
     "command": "experiments/benchmark/run.sh" + (" --quick" if sys.argv[3] == "1" else ""),
     "repeats": int(sys.argv[4]), "knitsim": sys.argv[2], "git_commit": commit,
     "created_utc": datetime.datetime.utcnow().isoformat() + "Z",
     "load_average": os.getloadavg(), "nproc": os.cpu_count()}
# The binary's own build stamp (git_commit is the repository's HEAD when the run ended).
first = os.path.join(os.path.dirname(sys.argv[1]), "runs", "four_corner-cvode-bdf-1", "manifest.json")
if os.path.exists(first):
    km = json.load(open(first))
    m["knitsim_build"] = {k: km.get(k) for k in ("git_commit", "build_type", "compiler", "libraries")}
json.dump(m, open(sys.argv[1], "w"), indent=2)
PY
echo "benchmark: wrote $OUT/runs.csv, $OUT/summary.csv, $OUT/manifest.json"
python3 "$here/summary.py" "$OUT"  # summary.md: the tables of README.md, from the CSV files
