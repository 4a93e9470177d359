#!/bin/sh
# knitsim knit under an address-space limit (ulimit -v): a chart either runs or is refused at
# set-up by its memory estimate with one line and exit 2 (docs/knit.md, "Memory"); never
# std::bad_alloc or exit 1. Usage: knit_memory_limit.sh KNITSIM
set -u
knitsim=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
chart() {  # chart WALES COURSES FILE: plain knit
  /usr/bin/python3 -c "import sys; print('\n'.join(['K' * int(sys.argv[1])] * int(sys.argv[2])))" "$1" "$2" >"$3"
}
# run LIMIT_KB CHART EXPECT: EXPECT = refused | runs | either
run() {
  sh -c "ulimit -v $1 && exec \"$knitsim\" knit --chart \"$2\" --no-pictures --out \"$dir/out\"" \
    >"$dir/stdout" 2>"$dir/stderr"
  status=$?
  lines=$(wc -l <"$dir/stderr")
  echo "$2 under ulimit -v $1 kB: exit $status, $lines stderr line(s): $(head -c 300 "$dir/stderr")"
  if grep -q "bad_alloc" "$dir/stderr" || [ "$status" -eq 1 ] || [ "$status" -gt 3 ]; then
    echo "FAIL: bad_alloc or an internal error"; fail=1
  fi
  case "$3:$status" in
    refused:2 | runs:0 | runs:3 | either:0 | either:2 | either:3) ;;
    *) echo "FAIL: expected it $3"; fail=1 ;;
  esac
  if [ "$status" -eq 2 ] && [ "$lines" -ne 1 ]; then echo "FAIL: a refusal is one line"; fail=1; fi
  if [ "$3" = refused ] && ! grep -q "needs about .* MB" "$dir/stderr"; then
    echo "FAIL: the refusal names the size"; fail=1
  fi
  rm -rf "$dir/out"
}
limit=1572864  # 1.5 GiB of address space
chart 4000 3 "$dir/wide.chart"    # ~3 GB estimated with contact: refused at set-up
chart 40 3 "$dir/narrow.chart"    # a few MB: runs
chart 200 3 "$dir/middle.chart"   # ~200 MB: runs, or is refused cleanly
run $limit "$dir/wide.chart" refused
run $limit "$dir/narrow.chart" runs
run $limit "$dir/middle.chart" either
run 400000 "$dir/middle.chart" either  # tight: the estimate or, failing it, the one-line backstop
exit $fail
