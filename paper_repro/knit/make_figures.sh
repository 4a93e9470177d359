#!/usr/bin/env bash
# Paper 2 (knit loops) figures: runs `knitsim knit` on the committed charts in models/charts/
# with paper 2's network (wale + course springs, --set knit.network=paper), with the stabilised
# network without yarn contact (--set knit.stabiliser=0.1 --set knit.contact=0) and with the
# default model (the stabilised network with yarn contact, no --set; pictures suffixed _contact),
# then a 40 x 40 chart with tucks: the default model, and without contact with cvode-bdf,
# implicit-euler (automatic dt = 1 s) and verlet. See README.md for which picture is which figure.
#
# Usage: paper_repro/knit/make_figures.sh   (from the repository root)
#   KNITSIM=path/to/knitsim   the binary (default build/knitsim)
#   OUT=folder                output folder (default out/knit_figures)
# Writes $OUT/<chart>-<paper|stabilised|contact>/ (the outputs of knitsim knit), $OUT/runs.csv (one row
# per run: chart, variant, integrator, status, steps, t_final, wall time, max displacement / r,
# min yarn clearance over the run / r and crossings changed, from summary.json's yarn block),
# $OUT/manifest.json (git commit, binary and build stamp, load) and $OUT/figures/ (below).
set -euo pipefail
cd "$(dirname "$0")/../.."
export KNITSIM=${KNITSIM:-build/knitsim}
py=/usr/bin/python3   # Debian's, with the standard library the scripts need
[ -x "$py" ] || py=python3
OUT=${OUT:-out/knit_figures}
CHARTS=models/charts
[ -x "$KNITSIM" ] || { echo "make_figures.sh: no knitsim binary at $KNITSIM (set KNITSIM)" >&2; exit 1; }
mkdir -p "$OUT"
echo "chart,variant,integrator,status,steps,t_final_s,wall_s,max_displacement_over_r,min_clearance_over_r,crossings_changed" > "$OUT/runs.csv"

# run NAME VARIANT CHARTFILE ARGS...: one knitsim knit run into $OUT/NAME-VARIANT, one runs.csv row.
run() {
  local name=$1 variant=$2 chart=$3; shift 3
  local dir="$OUT/$name-$variant" status=0
  "$KNITSIM" knit --chart "$chart" --frames 8 --quiet --out "$dir" "$@" || status=$?
  if [ "$status" -ne 0 ] && [ "$status" -ne 3 ]; then
    echo "make_figures.sh: knitsim knit failed on $chart (exit $status)" >&2; exit 1
  fi
  "$py" - "$dir/summary.json" "$name" "$variant" >> "$OUT/runs.csv" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
y = s.get("yarn", {})
print(",".join(str(v) for v in [sys.argv[2], sys.argv[3], s["integrator"], s["status"],
      s["stats"]["steps"], s["t_final"], round(s["wall_seconds"], 4),
      round(s["max_displacement_over_r"], 4),
      round(y["clearance_min_over_r"], 4) if "clearance_min_over_r" in y else "",
      y.get("crossings_changed", "")]))
PY
  tail -n 1 "$OUT/runs.csv"
}

for chart in plain_jersey single_tuck several_tucks several_misses; do
  run "$chart" paper "$CHARTS/$chart.chart" --set knit.network=paper
  run "$chart" stabilised "$CHARTS/$chart.chart" --set knit.stabiliser=0.1 --set knit.contact=0
  # the default model: the stabilised network plus the yarn contact keeping centrelines
  # >= ~0.9 r apart (knit's default integrator is then the equilibrium solver).
  run "$chart" contact "$CHARTS/$chart.chart"
done

# tucks40.chart: a 40 x 40 jersey with 23 single tucks on a staggered grid (a timing benchmark,
# also used by experiments/benchmark/knit_atol.sh).
run tucks40 contact "$CHARTS/tucks40.chart" --no-pictures
nc=(--set knit.stabiliser=0.1 --set knit.contact=0)
run tucks40 stabilised-cvode-bdf "$CHARTS/tucks40.chart" "${nc[@]}" --integrator cvode-bdf
run tucks40 stabilised-implicit-euler "$CHARTS/tucks40.chart" "${nc[@]}" --integrator implicit-euler
run tucks40 stabilised-verlet "$CHARTS/tucks40.chart" "${nc[@]}" --integrator verlet
run tucks40 paper-cvode-bdf "$CHARTS/tucks40.chart" --integrator cvode-bdf --set knit.network=paper --set run.t_max=0.05
# The figure pictures, copied under the paper's figure numbers into $OUT/figures/. "During"
# (Fig. 8c) is the captured frame whose largest displacement is nearest half the final one.
mkdir -p "$OUT/figures"
for variant in paper stabilised contact; do
  cp "$OUT/plain_jersey-$variant/after.png" "$OUT/figures/fig8a_plain_jersey_$variant.png"
  cp "$OUT/single_tuck-$variant/before.png" "$OUT/figures/fig8b_single_tuck_before_$variant.png"
  during=$("$py" - "$OUT/single_tuck-$variant/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
half = 0.5 * s["max_displacement_over_r"]
f = min(s["frames"], key=lambda f: abs(f["max_displacement_over_r"] - half))
print("%03d" % f["index"])
PY
)
  cp "$OUT/single_tuck-$variant/frames/frame_$during.png" \
    "$OUT/figures/fig8c_single_tuck_during_$variant.png"
  cp "$OUT/single_tuck-$variant/after.png" "$OUT/figures/fig8d_single_tuck_after_$variant.png"
  cp "$OUT/several_tucks-$variant/after.png" "$OUT/figures/fig9_several_tucks_$variant.png"
  cp "$OUT/several_misses-$variant/after.png" "$OUT/figures/fig10_several_misses_$variant.png"
done
# manifest.json: the script, git commit, the binary and its build stamp, machine load.
"$py" - "$OUT" "$OUT/single_tuck-paper" <<'PY'
import sys, types
sys.path.insert(0, "experiments")
import expkit
expkit.write_manifest(types.SimpleNamespace(quick=False, out=sys.argv[1]), "knit_figures",
                      sample_run=types.SimpleNamespace(folder=sys.argv[2]),
                      command="paper_repro/knit/make_figures.sh")
PY
# features.csv (single_tuck), stitch_features.csv (every tuck and miss), then summary.md
"$py" paper_repro/knit/features.py "$OUT" > /dev/null
"$py" paper_repro/knit/summary.py "$OUT" > /dev/null
echo "make_figures.sh: outputs in $OUT (runs.csv, manifest.json, features.csv, stitch_features.csv, summary.md, figures/)"
