#!/usr/bin/env bash
# knitsim: set-up (same as run.sh) and the whole test suite (ctest).
set -euo pipefail
cd "$(dirname "$0")"
./run.sh --build-only
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j "${JOBS:-$(nproc)}"
