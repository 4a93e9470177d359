#!/usr/bin/env bash
# Rewrites the committed summary.md of every study (the tables of figures its README points at)
# from the study's committed CSV files, without running knitsim: experiments/<study>/summary.py
# over its committed folder (results/; scaling: data/; identifiability: the study folder), and
# paper_repro/knit/summary.py over paper_repro/knit/results (study name: knit).
# The output has no timestamps, so running it twice changes nothing.
#
#   experiments/tables.sh [NAME ...]     only these studies (folder names under experiments/)
#
# experiments/check_tables.py checks that the committed files are what this writes.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
py=/usr/bin/python3
[ -x "$py" ] || py=python3
found=0
for script in "$here"/*/summary.py "$here"/../paper_repro/knit/summary.py; do
  name=$(basename "$(dirname "$script")")
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  "$py" "$script"
  found=$((found + 1))
done
[ "$found" -gt 0 ] || { echo "tables: no experiments/<study>/summary.py matched: $*" >&2; exit 2; }
