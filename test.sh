#!/usr/bin/env bash
# knitsim: set-up (same as run.sh) and the whole test suite (ctest).
#   ./test.sh             Release build in build/, all tests
#   ./test.sh --sanitize  AddressSanitizer + UBSan build in build-sanitize/, all tests
set -euo pipefail
cd "$(dirname "$0")"
if [ "${1:-}" = "--sanitize" ]; then
  export BUILD_DIR=${BUILD_DIR:-build-sanitize}
  export KNITSIM_CMAKE_ARGS="-DKNITSIM_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo"
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0"
fi
./run.sh --build-only
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j "${JOBS:-$(nproc)}"
