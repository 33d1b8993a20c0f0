#!/usr/bin/env bash
# Builds the Debian package of cblox (CPack's DEB generator) in build-deb/, configured for
# prefix /usr so that the systemd units' ExecStart lines name /usr/bin. Prints the .deb path.
# Install it with `apt-get install ./build-deb/cblox_*.deb`.
# Usage: scripts/package.sh
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_DIR=build-deb
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr \
  -DCBLOX_BUILD_TESTS=OFF -DCBLOX_BUILD_BENCHMARKS=OFF
cmake --build "$BUILD_DIR" -j"$(nproc)"
(cd "$BUILD_DIR" && cpack -G DEB)
ls -1 "$BUILD_DIR"/cblox_*.deb
