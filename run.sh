#!/usr/bin/env bash
# knitsim: one command does the whole set-up and runs the main job.
#   ./run.sh               install missing Debian packages, build (Release), run the main job
#   ./run.sh --build-only  the same set-up, builds everything including the tests, no job
#                          (test.sh uses this)
# Environment: BUILD_DIR (default build), OUT_DIR (default out/run-<date-time>), JOBS (default
# nproc).
set -euo pipefail
cd "$(dirname "$0")"
case "${1:-}" in
  "" | --build-only) ;;
  -h | --help) sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  *) echo "run.sh: unknown argument '$1' (accepted: --build-only, --help)" >&2; exit 2 ;;
esac
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}

# Debian 12 packages the build and the report need (Debian's own packages only).
# libopenblas0-serial: CHOLMOD's supernodal factorisation (from 33 000 unknowns) is faster than
# the LDL^T ones with it and no faster with the reference BLAS (solvers/symmetric_factor.hpp).
PACKAGES=(cmake g++ make pkg-config
  libsundials-dev libsuitesparse-dev libopenblas0-serial libeigen3-dev catch2
  libcairo2-dev libtomlplusplus-dev nlohmann-json3-dev libcli11-dev
  python3-scipy python3-matplotlib libopenmpi-dev openmpi-bin libpagmo-dev
  python3-dev pybind11-dev python3-pybind11 python3-pytest
  ${KNITSIM_EXTRA_PACKAGES:-})  # test.sh --fuzz adds clang and libclang-rt-14-dev (libFuzzer)

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
# The optimizers study's driver (experiments/optimizers), a target only where pagmo2 was found
# (CMakeLists.txt); without it run_all.sh reports that study as failed. The target list is read
# from the file every CMake generator writes (`--target help` lists no top-level target with
# Ninja).
if grep -qs '/knitsim_optimizers\.dir$' "$BUILD_DIR/CMakeFiles/TargetDirectories.txt"; then
  build knitsim_optimizers
fi
# The Python module (build/python, README.md) and the python study's C++ loop, where pybind11
# was found: the study of experiments/python imports the module.
for target in knitsim_python knitsim_python_bench; do
  if grep -qs "/$target\.dir\$" "$BUILD_DIR/CMakeFiles/TargetDirectories.txt"; then
    build "$target"
  fi
done

# The main job: the quick reproduction of paper 1's Tables 4 and 6 (with the Taguchi
# tuning, Fig. 13 and the fitted drapes), the integrator comparison on the built-in scenes, and
# every study of experiments/ in its quick mode; one report links them.
OUT_DIR=${OUT_DIR:-out/run-$(date +%Y%m%d-%H%M%S)}
mkdir -p "$OUT_DIR"
status=0
echo "[run] 1/3 paper 1 reproduction, quick preset -> $OUT_DIR/repro"
"$BUILD_DIR/knitsim" repro all --preset quick --jobs "$JOBS" --out "$OUT_DIR/repro" || status=1
echo "[run] 2/3 integrator comparison -> $OUT_DIR/demo"
"$BUILD_DIR/knitsim" demo --out "$OUT_DIR/demo" || status=1
echo "[run] 3/3 experiments, quick mode -> $OUT_DIR/experiments"
KNITSIM="$(cd "$BUILD_DIR" && pwd)/knitsim" experiments/run_all.sh --quick --out "$OUT_DIR/experiments" \
  || status=1
{
  echo "# knitsim run ($(date -u +%Y-%m-%dT%H:%M:%SZ), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown))"
  echo
  echo "- Paper 1 reproduction (quick preset): [repro/report.md](repro/report.md)"
  echo "- Integrator comparison and drape pictures: [demo/report.md](demo/report.md)"
  echo "- Experiments, quick mode: [experiments/summary.md](experiments/summary.md)"
  echo
  [ -f "$OUT_DIR/experiments/summary.md" ] && sed 's/^#/##/' "$OUT_DIR/experiments/summary.md"
} > "$OUT_DIR/report.md"
echo "[run] report: $OUT_DIR/report.md"
exit $status
