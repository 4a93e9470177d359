#!/usr/bin/env bash
# knitsim: one command does the whole set-up and runs the main job.
#   ./run.sh               install missing Debian packages, build (Release), run the main job
#   ./run.sh --build-only  the same set-up, builds everything including the tests, no job
#                          (test.sh uses this)
# Environment: BUILD_DIR (default build), OUT_DIR (default out/run), JOBS (default nproc).
set -euo pipefail
cd "$(dirname "$0")"
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}

# Debian 12 packages the build and the report need (Debian's own packages only).
PACKAGES=(cmake g++ make pkg-config
  libsundials-dev libsuitesparse-dev libeigen3-dev catch2
  libcairo2-dev libtomlplusplus-dev nlohmann-json3-dev libcli11-dev
  python3-scipy python3-matplotlib)

install_missing_packages() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "[setup] installing ${#missing[@]} Debian packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# build [TARGET]: configure (Release, out of source) and build TARGET, or everything.
build() {
  # KNITSIM_CMAKE_ARGS (set by test.sh --sanitize) comes last and may override the build type.
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release ${KNITSIM_CMAKE_ARGS:-} >/dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS" ${1:+--target "$1"}
}

install_missing_packages
if [ "${1:-}" = "--build-only" ]; then
  build  # everything, tests included (test.sh)
  exit 0
fi
build knitsim

OUT_DIR=${OUT_DIR:-out/run}
mkdir -p "$OUT_DIR"
"$BUILD_DIR/knitsim" demo --out "$OUT_DIR"
echo "[run] report: $OUT_DIR/report.md"
