#!/usr/bin/env bash
# What does a knitsim process cost before it does anything, and what does the smallest drape
# cost as a whole process? The dynamic loader's work grows with every shared library mapped, so
# the script also counts them.
#
#   experiments/benchmark/startup.sh [--n N] [--fresh] [--vs OTHER_KNITSIM] [KNITSIM]
#
# Times whole processes, start to exit (Python's perf_counter around posix_spawn .. wait4; CPU
# = the child's user + system time from wait4): `knitsim --version` and `knitsim drape --scene
# four_corner --no-pictures --out DIR` (all defaults, DIR rewritten each run, as a script looping
# over drapes would; with --fresh a new DIR every run, as docs/performance.md states its target),
# N runs each (default 21) after one warm-up run, and prints the medians. DIR is under $TMPDIR
# (default /tmp): its file system sets what the files cost (on an ext4 without a journal each new
# file costs more the more files were deleted there in the last half minute; on tmpfs little).
# With --vs the other binary runs in alternation with KNITSIM (A B B A A B ...) and the median of
# the pair-by-pair ratios A / B is printed too: alternation keeps the ratio fair when a shared
# machine's speed drifts. KNITSIM defaults to build/knitsim. Also prints how many shared
# libraries each binary maps at start (`ldd | wc -l`, the vdso and the loader included) and
# which it names itself (NEEDED). ~5 s for N = 21.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
N=21
OTHER=""
FRESH=0
usage="usage: $0 [--n N] [--fresh] [--vs OTHER_KNITSIM] [KNITSIM]"
KNITSIM=""
while [ $# -gt 0 ]; do
  case "$1" in
    --n) N=${2:?$usage}; shift ;;
    --vs) OTHER=${2:?$usage}; shift ;;
    --fresh) FRESH=1 ;;
    -*) echo "$usage" >&2; exit 2 ;;
    *) [ -z "$KNITSIM" ] || { echo "$usage" >&2; exit 2; }; KNITSIM=$1 ;;
  esac
  shift
done
KNITSIM=${KNITSIM:-$root/build/knitsim}
[[ "$N" =~ ^[1-9][0-9]*$ ]] || { echo "startup: --n = $N: must be an integer >= 1" >&2; exit 2; }
for exe in "$KNITSIM" ${OTHER:+"$OTHER"}; do
  [ -x "$exe" ] || { echo "startup: $exe is not an executable (run ./run.sh --build-only)" >&2; exit 2; }
  echo "$exe: $(ldd "$exe" | wc -l) libraries mapped (ldd); NEEDED:" \
    "$(readelf -d "$exe" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | tr '\n' ' ')"
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
/usr/bin/python3 - "$N" "$FRESH" "$work" "$KNITSIM" ${OTHER:+"$OTHER"} <<'PY'
import os, statistics, sys, time

n, fresh, work, exes = int(sys.argv[1]), sys.argv[2] == "1", sys.argv[3], sys.argv[4:]
cases = {"--version": ["--version"],
         "drape four_corner --no-pictures": ["drape", "--scene", "four_corner", "--no-pictures"]}
devnull = os.open(os.devnull, os.O_WRONLY)

def run(argv):
    """Wall and CPU seconds of one whole process."""
    actions = [(os.POSIX_SPAWN_DUP2, devnull, 1), (os.POSIX_SPAWN_DUP2, devnull, 2)]
    start = time.perf_counter()
    pid = os.posix_spawn(argv[0], argv, os.environ, file_actions=actions)
    _, status, usage = os.wait4(pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"startup: {' '.join(argv)} failed (exit {os.waitstatus_to_exitcode(status)})")
    return wall, usage.ru_utime + usage.ru_stime

print("case,binary,median_wall_ms,median_cpu_ms" + (",median_wall_ratio_A_over_B" if len(exes) > 1 else ""))
for name, args in cases.items():
    wall = [[] for _ in exes]
    cpu = [[] for _ in exes]
    for i in range(n + 1):  # run 0 warms the caches and is not counted
        for k in (range(len(exes)) if i % 2 == 0 else reversed(range(len(exes)))):
            exe = exes[k]
            out = f"{work}/drape{k}" + (f"-{i}" if fresh else "")
            extra = ["--out", out] if args[0] == "drape" else []
            w, c = run([exe] + args + extra)
            if i > 0:
                wall[k].append(w)
                cpu[k].append(c)
    for k, exe in enumerate(exes):
        label = "A" if k == 0 else "B"
        line = f"{name},{label} {exe},{1e3 * statistics.median(wall[k]):.2f},{1e3 * statistics.median(cpu[k]):.1f}"
        if len(exes) > 1:
            ratio = statistics.median(a / b for a, b in zip(wall[0], wall[1]))
            line += f",{ratio:.2f}" if k == 0 else ","
        print(line)
PY
