#!/usr/bin/env bash
# Offline replay speed: records a simulated run with lcm-logger (scripts/record_sim.sh, in a
# private network namespace), then replays it with cblox-replay (tracker + mapper in one
# process, deterministic) and prints frames per second and the speed against real time
# (the sensor's 20 Hz).
#
# Usage: scripts/bench_replay.sh [--scene room|hall|town] [--trajectory loop|orbit|...]
#                                [--laps N] [--frames N] [--out DIR] [--keep-log]
# Writes DIR/SCENE.lcmlog (deleted afterwards unless --keep-log: 2.5 MB a frame) and
# DIR/SCENE_replay/ (mesh.ply, keyframes.tum, frame_poses.tum, replay.json).
# Needs a build (scripts/build.sh); BUILD_DIR selects it.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
scene=room trajectory=loop laps=1 frames=0 out=out keep=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --trajectory) trajectory=$2; shift 2 ;;
    --laps) laps=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --keep-log) keep=1; shift ;;
    *) echo "bench_replay: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
bin=$(cd "$BUILD_DIR/daemon" && pwd)
log="$out/$scene.lcmlog"

# Record at 20 Hz, as a live run would be (lcm-logger keeps up; capture renders in time).
scripts/record_sim.sh "$scene" "$trajectory" "$laps" "$frames" "$log"
echo "bench_replay: recorded $(du -h "$log" | cut -f1) to $log"

"$bin/cblox-replay" "$log" --out "$out/${scene}_replay" --mapper-config config/mapper.yaml \
  --tracker-config config/tracker.yaml --pose-source tracker --initial-pose-from-gt \
  --progress-period 10
/usr/bin/env python3 - "$out/${scene}_replay/replay.json" "$scene" << 'PY'
import json, sys
s = json.load(open(sys.argv[1]))
frames, wall = s["tracker_frames"], s["wall_s"]
print(f"bench_replay: {sys.argv[2]}: {frames} frames in {wall:.1f} s = {frames / wall:.1f} frames/s "
      f"= {frames / wall / 20:.2f}x real time (20 Hz); tracker frame median "
      f"{s['tracker']['frame_ms_median']:.1f} ms; {s['tracker']['keyframes']} keyframes, "
      f"{s['tracker']['loops_closed']} loops; {s['mapper']['frames_integrated']} integrated, "
      f"{s['mapper']['subvolumes']} subvolumes")
PY
[[ $keep == 1 ]] || rm -f "$log"
