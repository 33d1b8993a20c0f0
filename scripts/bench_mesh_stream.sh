#!/usr/bin/env bash
# The live mesh stream and the viewer on a recorded run at the sensor's 20 Hz (issue 44, item
# 5): the log (scripts/record_sim.sh: cblox-capture's CBLOX_DEPTH and CBLOX_GT_POSE) is played
# with lcm-logplayer in real time into cblox-mapper (ground-truth poses, config/mapper.yaml)
# twice, in a private network namespace (scripts/netns-run.sh):
#   A. mesh_stream.enabled: false                 -> the mapper's CPU without the stream
#   B. the shipped settings (the stream at 1 Hz), cblox-viewer, one browser (Debian's
#      Chromium headless on the page) and cblox-bench-mesh-stream counting the bytes
# Prints, per run, the CPU share (CPU seconds / wall seconds of the playback, 1.0 = one core)
# of the mapper, of the mapper's threads that do the stream's work (its fusion/export worker
# "cblox-export", idle otherwise in ground-truth mode, and the copy thread "cblox-meshcopy":
# the stream's own cost, free of the run-to-run noise of the whole process), of the viewer, and the stream's bytes per second against the whole mesh
# resent each period (cblox-bench-mesh-stream). Writes DIR/mesh_stream_SCENE.json.
#
# Usage: scripts/bench_mesh_stream.sh --scene room|town [--frames N] [--out DIR]
#                                     [--log FILE] [--keep-log]
#   --log FILE   play this log (recorded with the same scene) instead of recording one
# Needs a build (BUILD_DIR, default build), lcm-logplayer (liblcm-bin), chromium and bc.
# Exit status: 0 done, 1 a process failed, 2 usage.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
scene=room frames=500 out=out log="" keep=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --log) log=$2; shift 2 ;;
    --keep-log) keep=1; shift ;;
    -h|--help) sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bench_mesh_stream: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
if [[ -z "$log" ]]; then
  log="$out/$scene.lcmlog"
  echo "recording $frames frames of sim:$scene into $log"
  scripts/record_sim.sh "$scene" loop 1 "$frames" "$log"
  [[ $keep -eq 1 ]] || trap 'rm -f "$log"' EXIT
fi
log=$(cd "$(dirname "$log")" && pwd)/$(basename "$log")
bin=$(cd "$BUILD_DIR/daemon" && pwd)
bench=$(cd "$BUILD_DIR/test/bench" && pwd)
work="$out/mesh_stream_${scene}_work"
rm -rf "$work"
mkdir -p "$work"
printf 'mesh_stream: {enabled: false}\n' > "$work/off.yaml"
printf '{}\n' > "$work/on.yaml"

# run NAME CONFIG WITH_VIEWER: one playback; prints "NAME mapper CORES viewer CORES".
BIN="$bin" BENCH="$bench" LOG="$log" WORK="$work" scripts/netns-run.sh bash -c '
  set -uo pipefail
  url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
  cpu() { local f=($(sed "s/^.*) //" /proc/$1/stat)); echo $((f[11] + f[12])); }
  # CPU ticks of the threads of process $1 named $2 (summed).
  thread_cpu() {
    local t total=0
    for t in /proc/$1/task/*; do
      [[ "$(cat $t/comm 2> /dev/null)" == "$2" ]] || continue
      local f=($(sed "s/^.*) //" $t/stat)); total=$((total + f[11] + f[12]))
    done
    echo $total
  }
  run() {
    local name=$1 config=$2 viewer=$3 pids=() mapper v=""
    "$BIN/cblox-mapper" --config "$config" --output-dir "$WORK/$name" --lcm-url "$url" \
      --quiet > "$WORK/$name.mapper.log" 2>&1 &
    mapper=$!; pids+=($mapper)
    if [[ $viewer -eq 1 ]]; then
      "$BIN/cblox-viewer" --lcm-url "$url" --quiet > "$WORK/$name.viewer.log" 2>&1 &
      v=$!; pids+=($v)
      sleep 0.5
      chromium --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader \
        --window-size=1280,800 --log-level=3 --user-data-dir="$WORK/chromium" \
        --remote-debugging-port=9222 http://127.0.0.1:8090/ > /dev/null 2>&1 &
      pids+=($!)
      "$BENCH/cblox-bench-mesh-stream" --lcm-url "$url" --idle-s 4 \
        --json "$WORK/$name.stream.json" > "$WORK/$name.stream.txt" 2>&1 &
      counter=$!
    fi
    sleep 2
    local m0=$(cpu $mapper) v0=0 t0=$(date +%s.%N)
    local w0=$(thread_cpu $mapper cblox-export) c0=$(thread_cpu $mapper cblox-meshcopy)
    [[ -n "$v" ]] && v0=$(cpu $v)
    lcm-logplayer --lcm-url "$url" "$LOG" > /dev/null 2>&1
    sleep 1.5  # the last period after the last frame
    local m1=$(cpu $mapper) v1=0 t1=$(date +%s.%N)
    local w1=$(thread_cpu $mapper cblox-export) c1=$(thread_cpu $mapper cblox-meshcopy)
    [[ -n "$v" ]] && v1=$(cpu $v)
    local hz=$(getconf CLK_TCK)
    local mc=$(echo "($m1 - $m0) / $hz / ($t1 - $t0)" | bc -l)
    local vc=0
    [[ -n "$v" ]] && vc=$(echo "($v1 - $v0) / $hz / ($t1 - $t0)" | bc -l)
    local sc=$(echo "($w1 - $w0 + $c1 - $c0) / $hz / ($t1 - $t0)" | bc -l)
    printf "%s mapper %.4f viewer %.4f wall %.1f stream_threads %.4f\n" "$name" "$mc" "$vc" \
      "$(echo "$t1 - $t0" | bc -l)" "$sc"
    [[ $viewer -eq 1 ]] && wait $counter
    kill -TERM "${pids[@]}" 2> /dev/null; wait "${pids[@]}" 2> /dev/null
    return 0
  }
  run off "$WORK/off.yaml" 0
  run on "$WORK/on.yaml" 1
' | tee "$work/cpu.txt"
cat "$work/on.stream.txt"
off=$(awk '$1 == "off" {print $3}' "$work/cpu.txt")
on=$(awk '$1 == "on" {print $3}' "$work/cpu.txt")
viewer=$(awk '$1 == "on" {print $5}' "$work/cpu.txt")
threads=$(awk '$1 == "on" {print $9}' "$work/cpu.txt")
printf 'mapper without the stream %.3f cores, with it %.3f (extra %.3f); its worker and copy threads %.3f; viewer with one browser %.3f\n' \
  "$off" "$on" "$(echo "$on - $off" | bc -l)" "$threads" "$viewer"
/usr/bin/python3 - "$work" "$out/mesh_stream_$scene.json" "$off" "$on" "$viewer" "$threads" <<'PY'
import json, sys
work, path, off, on, viewer, threads = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:])
stream = json.load(open(f"{work}/on.stream.json"))
json.dump({"mapper_cores_without_stream": off, "mapper_cores_with_stream": on,
           "mapper_extra_cores": on - off, "mapper_stream_thread_cores": threads,
           "viewer_cores": viewer, "stream": stream},
          open(path, "w"), indent=2)
PY
echo "wrote $out/mesh_stream_$scene.json"
