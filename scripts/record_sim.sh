#!/usr/bin/env bash
# Records a simulated run into an LCM log at the sensor's 20 Hz, as a live run would be:
# cblox-capture plays the scene while scripts/record.sh (lcm-logger) records its channels,
# both in a private network namespace (scripts/netns-run.sh). Used by the benchmarks that
# replay a run (bench_replay.sh, bench_pipeline_replay.sh).
#
# Usage: scripts/record_sim.sh SCENE TRAJECTORY LAPS FRAMES LOG
#   FRAMES 0 = the whole trajectory. LOG is overwritten (about 2.4 MB a frame).
# Needs a build (BUILD_DIR, default build). Exit status: cblox-capture's; 2 usage.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ $# -ne 5 ]]; then
  sed -n '7,8p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
bin=$(cd "${BUILD_DIR:-build}/daemon" && pwd)
CBLOX_BIN="$bin" SCENE="$1" TRAJ="$2" LAPS="$3" FRAMES="$4" LOG="$5" scripts/netns-run.sh bash -c '
  url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
  scripts/record.sh --lcm-url "$url" --force "$LOG" > /dev/null 2>&1 &
  logger=$!
  sleep 0.5
  status=0
  "$CBLOX_BIN/cblox-capture" --source "sim:$SCENE" --trajectory "$TRAJ" --laps "$LAPS" \
    --frames "$FRAMES" --rate 20 --lcm-url "$url" --quiet || status=$?
  sleep 0.5
  kill -INT $logger; wait $logger || true
  exit $status'
