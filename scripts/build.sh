#!/usr/bin/env bash
# Configures and builds cblox (Release, Ninja, ccache) into ${BUILD_DIR:-build}.
# Extra arguments are passed to CMake's configure step.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ccache_env.sh
BUILD_DIR=${BUILD_DIR:-build}
WERROR=OFF
if [[ "${CI:-}" == "true" ]]; then WERROR=ON; fi
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCBLOX_WERROR=$WERROR "$@"
cmake --build "$BUILD_DIR" -j"$(nproc)"
