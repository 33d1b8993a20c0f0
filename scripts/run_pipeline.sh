#!/usr/bin/env bash
# Runs the live pipeline on a simulated scene in a private network namespace (so it needs
# no multicast route and disturbs nothing else): cblox-capture plays the simulator in real
# time, cblox-tracker tracks the stereo pair (its first keyframe takes the first frame's
# exact pose, so its frame G is the scene's), cblox-mapper integrates the depth frames at the
# tracker's poses (or, with --poses ground_truth, at the simulator's exact poses, no
# tracker), then cblox-ctl asks for the mesh and cblox-eval measures it against the scene's
# exact mesh.
#
# Usage: scripts/run_pipeline.sh [--scene room|hall|town] [--trajectory orbit|loop|...]
#                                [--laps N] [--rate HZ] [--frames N] [--out DIR] [--name NAME]
#                                [--poses tracker|ground_truth]   (default tracker)
#                                [--mapper-config FILE]   (default config/mapper.yaml)
#                                [--slice Z]  (planning on: after the mesh, write the
#                                 distance field's slice at height Z, NAME_slice.png)
#                                [--query "X Y Z ..."]  (planning on: print the planning
#                                 map's answer at these points of G, cblox-ctl distance)
#                                [--tracker-config FILE]  (default config/tracker.yaml)
#                                [--capture-config FILE]  (default config/capture.yaml; e.g.
#                                 config/examples/sim_stereo_depth.yaml: depth from SGBM)
#                                [--source SPEC]  a dataset instead of a scene, e.g.
#                                 euroc:DIR, kitti:DIR (no exact scene: the mesh is written
#                                 and pictured by height, DIR/NAME_height.png, not evaluated)
#                                [--up AXIS]  datasets: the axis of G that points up (default
#                                 -y: the first camera's frame; z for a z-up ground truth)
# Writes DIR/NAME.ply (the mapper's mesh), DIR/NAME_gt.ply (exact scene), DIR/NAME_eval.json
# and DIR/NAME_error.png. Needs a build (scripts/build.sh); BUILD_DIR selects it.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
scene=room trajectory=orbit laps=1 rate=20 frames=0 out=out name="" mapper_config=config/mapper.yaml
poses=tracker tracker_config=config/tracker.yaml capture_config=config/capture.yaml source=""
slice="" query="" up=-y
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --trajectory) trajectory=$2; shift 2 ;;
    --laps) laps=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --name) name=$2; shift 2 ;;
    --mapper-config) mapper_config=$2; shift 2 ;;
    --slice) slice=$2; shift 2 ;;
    --query) query=$2; shift 2 ;;
    --tracker-config) tracker_config=$2; shift 2 ;;
    --capture-config) capture_config=$2; shift 2 ;;
    --source) source=$2; shift 2 ;;
    --poses) poses=$2; shift 2 ;;
    --up) up=$2; shift 2 ;;
    *) echo "run_pipeline: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
case "$poses" in
  tracker|ground_truth) ;;
  *) echo "run_pipeline: --poses must be tracker or ground_truth, got '$poses'" >&2; exit 2 ;;
esac
name=${name:-pipeline_$scene}
mkdir -p "$out"
out=$(cd "$out" && pwd)
bin=$(cd "$BUILD_DIR/daemon" && pwd)

if [[ "${CBLOX_IN_NETNS:-}" != "1" ]]; then
  CBLOX_IN_NETNS=1 exec scripts/netns-run.sh "$0" --scene "$scene" --trajectory "$trajectory" --laps "$laps" \
    --rate "$rate" --frames "$frames" --out "$out" --name "$name" \
    --mapper-config "$mapper_config" --tracker-config "$tracker_config" --poses "$poses" \
    --capture-config "$capture_config" ${source:+--source "$source"} ${slice:+--slice "$slice"} ${query:+--query "$query"} \
    --up "$up"
fi
# A scene of the simulator (exact ground truth), or a dataset given with --source.
sim=true
if [[ -n $source && $source != sim:* ]]; then sim=false; fi
source=${source:-sim:$scene}
capture_args=(--config "$capture_config" --source "$source" --rate "$rate" --frames "$frames")
if $sim; then capture_args+=(--trajectory "$trajectory" --laps "$laps"); fi
initial_pose=()
if $sim; then initial_pose=(--initial-pose-from-gt); fi

url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
"$bin/cblox-mapper" --config "$mapper_config" --pose-source "$poses" --output-dir "$out" \
  --lcm-url "$url" ${slice:+--planning} ${query:+--planning} > "$out/${name}_mapper.log" 2>&1 &
mapper=$!
tracker=""
if [[ "$poses" == tracker ]]; then
  "$bin/cblox-tracker" --config "$tracker_config" "${initial_pose[@]}" --lcm-url "$url" \
    > "$out/${name}_tracker.log" 2>&1 &
  tracker=$!
fi
trap 'kill -TERM $mapper $tracker 2>/dev/null || true' EXIT
start_ns=$(date +%s%N)
sleep 1
echo "pipeline: capture $source at $rate Hz ->" \
  "$([[ -n $tracker ]] && echo "cblox-tracker -> ")cblox-mapper ($poses poses)"
"$bin/cblox-capture" "${capture_args[@]}" --lcm-url "$url"
sleep 2  # let the tracker and the mapper finish the last frames
"$bin/cblox-ctl" --lcm-url "$url" --timeout 30 status
"$bin/cblox-ctl" --lcm-url "$url" --timeout 120 export-mesh "$name.ply"
if [[ -n $slice ]]; then
  "$bin/cblox-ctl" --lcm-url "$url" --timeout 120 esdf-slice --z "$slice" --out "${name}_slice.png"
fi
if [[ -n $query ]]; then
  echo "pipeline: the planning map at $query:"
  # shellcheck disable=SC2086  # the points are words
  "$bin/cblox-ctl" --lcm-url "$url" --timeout 30 distance $query
fi
# CPU share and peak memory of each process over the run (from /proc, before it exits).
hz=$(getconf CLK_TCK)
wall=$(( ($(date +%s%N) - start_ns) / 1000000 ))
usage() {  # usage NAME PID
  local ticks rss
  ticks=$(awk '{print $14 + $15}' "/proc/$2/stat")
  rss=$(awk '/^VmHWM:/ {print $2}' "/proc/$2/status")
  awk -v n="$1" -v t="$ticks" -v hz="$hz" -v w="$wall" -v r="$rss" 'BEGIN {
    printf "pipeline: %s used %.1f s CPU over %.1f s (%.0f %% of one core), peak RSS %.1f MiB\n",
           n, t / hz, w / 1000, 100 * (t / hz) / (w / 1000), r / 1024 }'
}
[[ -n $tracker ]] && usage cblox-tracker "$tracker"
usage cblox-mapper "$mapper"
kill -TERM $mapper
wait $mapper || { echo "pipeline: cblox-mapper exited with $?" >&2; exit 1; }
if [[ -n $tracker ]]; then
  kill -TERM "$tracker"
  wait "$tracker" || { echo "pipeline: cblox-tracker exited with $?" >&2; exit 1; }
  grep -E "^cblox-tracker: (stopped|tracked|loop)" "$out/${name}_tracker.log" | tail -3 || true
fi
trap - EXIT
if ! $sim; then
  echo "pipeline: mesh $out/$name.ply (no exact scene for $source; mapper log $out/${name}_mapper.log)"
  "$bin/cblox-eval" --mesh "$out/$name.ply" --height-png "$out/${name}_height.png" --up "$up"
  exit 0
fi
"$bin/cblox-capture" --config "$capture_config" --source "$source" --write-scene "$out/${name}_gt.ply" > /dev/null
"$bin/cblox-eval" --gt-mesh "$out/${name}_gt.ply" --mesh "$out/$name.ply" --max-error 0.04 \
  --voxel-size "$(awk '/^  voxel_size:/ {print $2; exit}' "$mapper_config")" \
  --json "$out/${name}_eval.json" --error-png "$out/${name}_error.png"
echo "pipeline: mesh $out/$name.ply (mapper log $out/${name}_mapper.log)"
