#!/usr/bin/env bash
# The Python module's overhead against a C++ loop and the CLI, and its two-thread speed-up
# (README.md). Usage: experiments/python/run.sh [--quick] [--out DIR] [--runs N] [--reps R]
#   [--cli-calls C]
set -euo pipefail
exec /usr/bin/python3 "$(dirname "$0")/bench.py" "$@"
