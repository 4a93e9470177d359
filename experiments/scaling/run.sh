#!/usr/bin/env bash
# Scaling study (how cost grows with the number of
# particles): four_corner drapes of one 50 x 50 cm sheet refined from 11 x 11 to 101 x 101
# particles (and 141 x 141 in full mode) with cvode-bdf (Schur LDL^T and KLU), cvode-bdf-gmres,
# implicit-euler and the equilibrium solver on the full grid, the equilibrium solver as the
# default runs it (model.symmetry = auto: the eighth here; label equilibrium-auto), and `static`
# on the eighth the scene requires (model.symmetry = eighth; solver label static-eighth). CPU time, steps and peak memory per
# run; growth exponents fitted by plot.py (reads only the CSV; repeated runs enter as medians).
#
#   experiments/scaling/run.sh [--quick | --target [--repeats R]] [--grids "N ..."]
#                              [--solver "LABEL ..."] [--out DIR] [--max-wall S]
#
# --target: the target "a 101 x 101 four_corner equilibrium in <= 5 s" only: n = 100
# with static on the eighth and on the quarter, cvode-bdf on the eighth and the equilibrium
# solver on the whole sheet and as the default runs it, R rounds (default 3) of the five in turn
# (runs interleaved, so load drifts hit all alike); default DIR out/scaling-target.
# --grids: cells per side to run instead of the mode's list; --solver: only the runs with these
# labels (cvode-bdf-ldl (--factorization auto: block below 33 000 unknowns, supernodal from
# there), cvode-bdf-ldl-simplicial, -block, -supernodal (the same with that --factorization:
# run only at n >= 60, where the back ends part ways), cvode-bdf-klu,
# cvode-bdf-gmres (its default preconditioner, the lagged
# Schur LDL^T), cvode-bdf-gmres-bj (block-Jacobi), implicit-euler, equilibrium, equilibrium-auto,
# static-eighth, static-quarter, cvode-bdf-eighth), e.g. --solver static-eighth --grids "100 140 200" for the
# reduced model on grids the full-grid solvers cannot reach in useful time.
#
# Refinement: cells per side n, natural length L0 = W / n (W = 0.50 m, so the sheet is the
# same at every n), stiffness k = 852 N/m per spring (one spring stands for a strip of
# fabric whose tensile stiffness does not depend on its length-to-width ratio when refined in
# both directions), damping scaled with the particle mass, c = 12 N s/m x (L0 / 0.049 m)^2,
# i.e. the paper's damping rate c/m at every n (docs/numerics.md: the paper's damping is absolute per
# particle, so an unscaled c would add total damping under refinement and slow the settling
# without changing the equilibrium). Each run is capped at --max-wall seconds of wall time
# (status wall_limit then; default 1800 s, 60 s with --quick: enough for n = 40 on a quiet
# machine, and cvode-bdf-gmres-bj, which does not settle at n >= 20, uses all of it; on a loaded machine raise
# it). Grids: n = 10 20 40 60 80 100
# 140; --quick: 10 20 40.
# --quick also runs nested.py --quick (the coarse-to-fine start at n = 20: nested_runs.csv).
# Writes DIR/runs.csv (one row per run), DIR/manifest.json (with the binary's build stamp as
# knitsim_build), DIR/runs/<n>-<solver>/ (each knitsim output folder and its /usr/bin/time -v
# log); default DIR = out/scaling.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
KNITSIM=${KNITSIM:-$root/build/knitsim}
QUICK=0
TARGET=0
REPEATS=3
OUT=
MAX_WALL=
usage="usage: $0 [--quick | --target [--repeats R]] [--grids \"N ...\"] [--solver \"LABEL ...\"] [--out DIR] [--max-wall S]"
GRIDS_OPT=
SOLVER=
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) QUICK=1 ;;
    --target) TARGET=1 ;;
    --repeats) REPEATS=${2:-}; shift ;;
    --grids) GRIDS_OPT=${2:-}; shift ;;
    --solver) SOLVER=${2:-}; shift ;;
    --out) OUT=${2:-}; shift ;;
    --max-wall) MAX_WALL=${2:-}; shift ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
  shift
done
case "$REPEATS" in '' | *[!0-9]* | 0) echo "scaling: --repeats must be an integer >= 1" >&2; exit 2 ;; esac
for g in $GRIDS_OPT; do
  case "$g" in '' | *[!0-9]* | 0 | 1) echo "scaling: --grids: $g is not an integer >= 2" >&2; exit 2 ;; esac
done
for label in $SOLVER; do
  case "$label" in
    cvode-bdf-ldl | cvode-bdf-ldl-simplicial | cvode-bdf-ldl-block | cvode-bdf-ldl-supernodal | cvode-bdf-klu | cvode-bdf-gmres | cvode-bdf-gmres-bj | implicit-euler | equilibrium | equilibrium-auto | static-eighth | static-quarter | cvode-bdf-eighth) ;;
    *) echo "scaling: --solver $label not in {cvode-bdf-ldl,cvode-bdf-ldl-simplicial,cvode-bdf-ldl-block,cvode-bdf-ldl-supernodal,cvode-bdf-klu,cvode-bdf-gmres,cvode-bdf-gmres-bj,implicit-euler,equilibrium,equilibrium-auto,static-eighth,static-quarter,cvode-bdf-eighth}" >&2; exit 2 ;;
  esac
done
[ "$QUICK$TARGET" != 11 ] || { echo "scaling: --quick and --target exclude each other" >&2; exit 2; }
if [ -z "$OUT" ]; then
  if [ "$TARGET" = 1 ]; then OUT=$root/out/scaling-target; else OUT=$root/out/scaling; fi
fi
[ -x "$KNITSIM" ] || { echo "scaling: $KNITSIM not built (run ./run.sh --build-only)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "scaling: /usr/bin/time (GNU time) is needed for peak memory" >&2; exit 2; }
if [ "$QUICK" = 1 ]; then GRIDS="10 20 40"; MAX_WALL=${MAX_WALL:-60};
elif [ "$TARGET" = 1 ]; then GRIDS="100"; MAX_WALL=${MAX_WALL:-600};
else GRIDS="10 20 40 60 80 100 140"; MAX_WALL=${MAX_WALL:-1800}; fi
[ -z "$GRIDS_OPT" ] || GRIDS=$GRIDS_OPT
mkdir -p "$OUT/runs"
runs_csv=$OUT/runs.csv
echo "n,particles,dof,natural_length_m,damping_Ns_per_m,solver,status,t_final,steps,rhs_evals,jac_evals,lin_setups,nonlin_iters,residual,centre_sag_m,cpu_seconds,wall_seconds,max_rss_kb,integrated_dof,factorisations,round,factorization,factor_nonzeros,factor_flops" > "$runs_csv"

# One drape: run n solver integrator [knitsim options...]; appends a row to runs.csv (ROUND:
# the repeat, in the folder name and the last column).
ROUND=1
run() {
  local n=$1 solver=$2 integ=$3; shift 3
  [ -z "$SOLVER" ] || [[ " $SOLVER " == *" $solver "* ]] || return 0
  local dir=$OUT/runs/$n-$solver-r$ROUND
  local L0 c
  L0=$(python3 -c "print(repr(0.50 / $n))")
  c=$(python3 -c "print(repr(12.0 * ((0.50 / $n) / 0.049) ** 2))")
  rm -rf "$dir"; mkdir -p "$dir"
  # The whole sheet unless the caller names a reduction (a key may be given once).
  local whole=(--set model.symmetry=none)
  case " $* " in *model.symmetry=*) whole=() ;; esac
  /usr/bin/time -v -o "$dir/time.txt" "$KNITSIM" drape --scene four_corner \
    --set model.natural_length="$L0" --set model.damping="$c" --integrator "$integ" \
    --max-wall "$MAX_WALL" --quiet --out "$dir/drape" "${whole[@]}" "$@" > "$dir/stdout.txt" 2>&1 || true
  python3 - "$dir" "$n" "$solver" "$L0" "$c" "$ROUND" >> "$runs_csv" <<'PY'
import json, re, sys
d, n, solver, L0, c, rnd = sys.argv[1:7]
rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(d + "/time.txt").read())
try:
    s = json.load(open(d + "/drape/summary.json"))
except (OSError, ValueError):
    s = None
n = int(n)
if s is None:  # the run failed before writing its summary (e.g. out of memory): keep a row
    print(",".join([str(n), str((n + 1) ** 2), "", L0, c, solver, "failed"] + [""] * 10 +
                   [rss.group(1) if rss else "", "", "", rnd, "", "", ""]))
else:
    print(",".join(str(v) for v in [n, s["grid"]["particles"], s["grid"]["dof"],
          L0, c, solver, s["status"], repr(s["t_final"]), s["steps"], s["rhs_evals"],
          s["jac_evals"], s["lin_setups"], s["nonlin_iters"], repr(s["residual"]),
          repr(s["centre_sag_m"]), repr(s["cpu_seconds"]), repr(s["wall_seconds"]),
          rss.group(1) if rss else "", s["grid"]["integrated_dof"], s["factorisations"], rnd,
          s.get("factorization", ""), s.get("factor_nonzeros", ""), s.get("factor_flops", "")]))
PY
  tail -n 1 "$runs_csv"
}

eighth=(--set model.symmetry=eighth)
if [ "$TARGET" = 1 ]; then
  for ROUND in $(seq 1 "$REPEATS"); do
    for n in $GRIDS; do
      run "$n" static-eighth static "${eighth[@]}"
      run "$n" static-quarter static --set model.symmetry=quarter
      run "$n" cvode-bdf-eighth cvode-bdf "${eighth[@]}"
      run "$n" equilibrium equilibrium
      run "$n" equilibrium-auto equilibrium --set model.symmetry=auto
    done
  done
else
  for n in $GRIDS; do
    run "$n" cvode-bdf-ldl cvode-bdf --newton-solver ldl
    # The three factorisation back ends side by side where they part ways (11 151 unknowns on).
    if [ "$n" -ge 60 ]; then
      for f in simplicial block supernodal; do
        run "$n" "cvode-bdf-ldl-$f" cvode-bdf --newton-solver ldl --factorization "$f"
      done
    fi
    run "$n" cvode-bdf-klu cvode-bdf --newton-solver klu
    run "$n" cvode-bdf-gmres cvode-bdf-gmres
    run "$n" cvode-bdf-gmres-bj cvode-bdf-gmres --gmres-preconditioner block-jacobi
    run "$n" implicit-euler implicit-euler
    run "$n" equilibrium equilibrium
    run "$n" equilibrium-auto equilibrium --set model.symmetry=auto
    run "$n" static-eighth static "${eighth[@]}"
  done
fi

# The coarse-to-fine start (nested.py; its full mode is run on its own, README) at n = 20.
[ "$QUICK" = 1 ] && /usr/bin/python3 "$here/nested.py" --quick --keep-runs --out "$OUT"

commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
mode=
[ "$QUICK" = 1 ] && mode=" --quick"
[ "$TARGET" = 1 ] && mode=" --target --repeats $REPEATS"
[ -z "$GRIDS_OPT" ] || mode="$mode --grids \"$GRIDS_OPT\""
[ -z "$SOLVER" ] || mode="$mode --solver \"$SOLVER\""
python3 - "$OUT/manifest.json" "$KNITSIM" "$mode" "$MAX_WALL" "$commit" "$GRIDS" <<'PY'
import datetime, glob, json, os, sys
m = {"experiment": "scaling",
     "command": "experiments/scaling/run.sh" + sys.argv[3],
     "grids_n": [int(g) for g in sys.argv[6].split()], "max_wall_seconds": float(sys.argv[4]),
     "knitsim": sys.argv[2], "git_commit": sys.argv[5],
     "created_utc": datetime.datetime.utcnow().isoformat() + "Z",
     "load_average": os.getloadavg(), "nproc": os.cpu_count()}
# The binary's own build stamp (git_commit is the repository's HEAD when the study ended).
for kp in sorted(glob.glob(os.path.join(os.path.dirname(sys.argv[1]), "runs", "*", "drape", "manifest.json"))):
    km = json.load(open(kp))
    m["knitsim_build"] = {k: km.get(k) for k in ("git_commit", "build_type", "compiler", "libraries")}
    break
json.dump(m, open(sys.argv[1], "w"), indent=2)
PY
echo "scaling: wrote $runs_csv and $OUT/manifest.json; plot: /usr/bin/python3 $here/plot.py $OUT"
