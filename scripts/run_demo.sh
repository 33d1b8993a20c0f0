#!/usr/bin/env bash
# The main job: installs what is needed, builds, integrates the built-in synthetic room
# (an analytic scene rendered along an orbit) with the fast integrator and writes a
# coloured PLY mesh. Usage: scripts/run_demo.sh [output.ply] [extra cblox-integrate args]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
out=${1:-out/demo_room.ply}
shift || true
mkdir -p "$(dirname "$out")"
"$BUILD_DIR/daemon/cblox-integrate" --config config/integrate.yaml --source synthetic-room \
  --output "$out" "$@"
