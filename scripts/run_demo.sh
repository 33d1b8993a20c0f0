#!/usr/bin/env bash
# The main job: installs what is needed, builds, and runs the whole live pipeline on the
# built-in simulated living room: cblox-capture renders the room along an orbit (Embree ray
# tracer, stereo + depth rig, exact ground truth) and publishes it over LCM in real time
# (20 Hz); cblox-tracker tracks the stereo pair (sparse SLAM: ORB features, local BA, loop
# closing) and publishes frame poses, keyframes and keyframe pose updates; cblox-mapper
# integrates the depth frames into TSDF subvolumes at the tracker's poses; cblox-ctl asks
# it for the global mesh; cblox-eval measures the mesh against the room's exact mesh.
# Everything runs in a private network namespace (scripts/run_pipeline.sh).
# Usage: scripts/run_demo.sh [extra run_pipeline.sh args, e.g. --scene hall --rate 10,
#                             --poses ground_truth for the mapper alone]
# Outputs: out/demo_room.ply (the mesh), out/demo_room_gt.ply (ground truth),
#          out/demo_room_eval.json and out/demo_room_error.png (evaluation).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
bash scripts/run_pipeline.sh --scene room --trajectory orbit --rate 20 --out out \
  --name demo_room "$@"
