#!/usr/bin/env bash
# Configures and builds cblox (Release, Ninja, ccache) into ${BUILD_DIR:-build}.
# Extra arguments are passed to CMake's configure step. CBLOX_TARGETS (space-separated) builds
# only those targets (scripts/run_demo.sh: the binaries the demo runs, not every test and
# bench); unset, everything.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ccache_env.sh
BUILD_DIR=${BUILD_DIR:-build}
WERROR=OFF
if [[ "${CI:-}" == "true" ]]; then WERROR=ON; fi
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCBLOX_WERROR=$WERROR "$@"
targets=()
for t in ${CBLOX_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$BUILD_DIR" "${targets[@]}" -j"$(nproc)"
