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
# The mapper also keeps its distance fields (--planning): at the end cblox-ctl writes a slice
# of the distance field at 1 m height and asks the distance at two points, the room's
# centre and 0.5 m from the wall x = 0.
# Outputs: out/demo_room.ply (the mesh), out/demo_room_gt.ply (ground truth),
#          out/demo_room_eval.json and out/demo_room_error.png (evaluation),
#          out/demo_room_slice.png (the distance field at z = 1 m, with the camera's path).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# Only what the demo runs (and the vocabulary the tracker loads): a first mesh without
# building every test and bench (scripts/test.sh builds everything).
CBLOX_TARGETS="cblox-capture cblox-tracker cblox-mapper cblox-ctl cblox-eval cblox_vocabulary_file" \
  bash scripts/build.sh
bash scripts/run_pipeline.sh --scene room --trajectory orbit --rate 20 --out out \
  --name demo_room --slice 1.0 --query "2.5 3.4 1.0 0.5 3.4 1.0" "$@"
