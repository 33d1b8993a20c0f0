#!/usr/bin/env bash
# The main job: installs what is needed, builds, renders the built-in simulated living room
# (Embree ray tracer, stereo + depth rig flying an orbit, exact ground truth), integrates the
# depth frames with the fast integrator into a TSDF volume, writes a coloured PLY mesh, and
# evaluates it against the scene's exact mesh (accuracy, completeness, error picture).
# Usage: scripts/run_demo.sh [output.ply] [extra cblox-integrate args]
# Outputs: out/demo_room.ply (mesh), out/demo_room_gt.ply (ground truth),
#          out/demo_eval.json and out/demo_error.png (evaluation).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
out=${1:-out/demo_room.ply}
shift || true
mkdir -p "$(dirname "$out")"
base="${out%.ply}"
"$BUILD_DIR/daemon/cblox-integrate" --config config/integrate.yaml --source sim:room \
  --trajectory orbit --output "$out" --write-ground-truth "${base}_gt.ply" "$@"
"$BUILD_DIR/daemon/cblox-eval" --gt-mesh "${base}_gt.ply" --mesh "$out" --max-error 0.02 \
  --json "$(dirname "$out")/demo_eval.json" --error-png "$(dirname "$out")/demo_error.png"
