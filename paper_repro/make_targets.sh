#!/usr/bin/env bash
# Synthetic targets of paper 1's reproduction (paper_repro/data/README.md, src/fit/synthetic_targets.hpp).
#
#   paper_repro/make_targets.sh           regenerates the 18 committed files
#                                         paper_repro/data/targets/{twin,cross}_sample{1..9}.csv
#   paper_repro/make_targets.sh --floor   prints the Eq. 5 model error floor per sample: the
#                                         objective between the noise-free twin and the
#                                         noise-free cross target, four_corner and two_corner
#                                         (the twin's edges come from `knitsim drape`, the run
#                                         the twin target is made of; see the files' comments)
#
# Builds knitsim first if needed (Release, in $KNITSIM_BUILD, default ./build). Run time and
# results: paper_repro/data/README.md.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
build=${KNITSIM_BUILD:-$root/build}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target knitsim >/dev/null
knitsim=$build/knitsim
seed=2017 noise=0.5 photos=5

if [ "${1:-}" != "--floor" ]; then
  "$knitsim" targets --set all --samples 1-9 --seed $seed --noise-mm $noise --photos $photos \
    --out "$here/data/targets"
  exit 0
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$knitsim" targets --set all --samples 1-9 --noise-mm 0 --out "$tmp" --quiet
echo "sample,four_corner_floor_percent,two_corner_floor_percent"
for s in 1 2 3 4 5 6 7 8 9; do
  row=$s
  for scene in four_corner two_corner; do
    # The comment line "<scene> noise-free edges = knitsim drape ..." of the twin file.
    cmd=$(sed -n "s/^# $scene noise-free edges = knitsim //p" "$tmp/twin_sample$s.csv")
    # shellcheck disable=SC2086  # the recorded command is word-split on purpose
    "$knitsim" $cmd --target "$tmp/cross_sample$s.csv" --out "$tmp/drape-$s-$scene" >/dev/null
    row=$row,$(/usr/bin/python3 -c \
      'import json,sys; print("%.4g" % json.load(open(sys.argv[1]))["objective"])' \
      "$tmp/drape-$s-$scene/summary.json")
  done
  echo "$row"
done
