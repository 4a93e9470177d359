#!/usr/bin/env bash
# knitsim: one command does the whole set-up and runs the main job.
#   ./run.sh               install missing Debian packages, build (Release), run the main job
#   ./run.sh --build-only  the same set-up and build, no job (test.sh uses this)
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

build() {
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

install_missing_packages
build
[ "${1:-}" = "--build-only" ] && exit 0

OUT_DIR=${OUT_DIR:-out/run}
mkdir -p "$OUT_DIR"
"$BUILD_DIR/knitsim" demo --out "$OUT_DIR"
echo "[run] report: $OUT_DIR/report.md"
