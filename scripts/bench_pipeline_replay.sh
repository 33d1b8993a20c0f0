#!/usr/bin/env bash
# The whole pipeline at the sensor's rate from a recorded log (issue 17, item 5): a simulated
# run is recorded once with lcm-logger (scripts/record_sim.sh, the capture at 20 Hz), then played
# with lcm-logplayer in real time into cblox-tracker + cblox-mapper with the shipped configs
# (config/tracker.yaml, config/mapper.yaml; tracker poses), in a private network namespace
# (scripts/netns-run.sh). No renderer runs during the measurement: the processes see what
# they would see from real cameras. Once a second it samples each process's CPU time
# (/proc/PID/stat utime + stime) and RSS; at the end it reads both processes' own totals
# (their "stopped:" lines: frames processed, lost, dropped, rejected, integrated).
#
# Prints, and writes DIR/pipeline_SCENE.md (a BENCHMARKS.md-ready table) and
# DIR/pipeline_SCENE_cpu.svg (cores over time, per process):
#   - CPU share: CPU seconds / wall seconds of the replay (1.0 = one core), per process and
#     tracker + mapper together, over the whole replay and per 10 s window (max);
#   - peak RSS (VmHWM) per process;
#   - frames: played, tracked, lost, dropped (tracker queue), integrated, dropped (mapper).
#
# Usage: scripts/bench_pipeline_replay.sh [--scene room|hall|town] [--trajectory loop]
#                                         [--laps N] [--frames N] [--out DIR]
#                                         [--log FILE] [--keep-log]
#                                         [--tracker-config FILE] [--mapper-config FILE]
#   --log FILE   play this log (recorded before with the same scene) instead of recording
#   --tracker-config / --mapper-config  instead of config/tracker.yaml / config/mapper.yaml
#   --keep-log   keep DIR/SCENE.lcmlog (2.5 MB a frame; deleted by default)
# Needs a build (BUILD_DIR, default build) and lcm-logger / lcm-logplayer (liblcm-bin).
# Exit status: 0 done, 1 a process failed, 2 usage.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
scene=room trajectory=loop laps=2 frames=0 out=out log="" keep=0
tracker_config=config/tracker.yaml mapper_config=config/mapper.yaml
usage() { sed -n '2,29p' "$0" | sed 's/^# \{0,1\}//'; }
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --trajectory) trajectory=$2; shift 2 ;;
    --laps) laps=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --log) log=$2; shift 2 ;;
    --keep-log) keep=1; shift ;;
    --tracker-config) tracker_config=$2; shift 2 ;;
    --mapper-config) mapper_config=$2; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "bench_pipeline_replay: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
for tool in lcm-logger lcm-logplayer; do
  command -v "$tool" > /dev/null || { echo "bench_pipeline_replay: $tool not found (apt-get install liblcm-bin)" >&2; exit 1; }
done
for f in "$tracker_config" "$mapper_config"; do
  [[ -r "$f" ]] || { echo "bench_pipeline_replay: cannot read $f" >&2; exit 2; }
done
tracker_config=$(cd "$(dirname "$tracker_config")" && pwd)/$(basename "$tracker_config")
mapper_config=$(cd "$(dirname "$mapper_config")" && pwd)/$(basename "$mapper_config")
mkdir -p "$out"
out=$(cd "$out" && pwd)
bin=$(cd "$BUILD_DIR/daemon" && pwd)
work="$out/pipeline_${scene}_work"
rm -rf "$work"
mkdir -p "$work"
recorded=0
if [[ -z "$log" ]]; then
  log="$out/$scene.lcmlog"
  recorded=1
  echo "bench_pipeline_replay: recording sim:$scene ($trajectory, $laps laps) at 20 Hz to $log"
  scripts/record_sim.sh "$scene" "$trajectory" "$laps" "$frames" "$log"
  echo "bench_pipeline_replay: recorded $(du -h "$log" | cut -f1)"
fi
[[ -s "$log" ]] || { echo "bench_pipeline_replay: no log at $log" >&2; exit 1; }
log=$(cd "$(dirname "$log")" && pwd)/$(basename "$log")

# The replay, sampled. Inside the namespace: start both, sample while lcm-logplayer plays,
# give the last frames 3 s, stop both with SIGTERM and keep their exit status.
CBLOX_BIN="$bin" LOG="$log" WORK="$work" TRACKER_CONFIG="$tracker_config" \
  MAPPER_CONFIG="$mapper_config" scripts/netns-run.sh bash -c '
  set -u
  url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
  cd "$WORK"
  "$CBLOX_BIN/cblox-mapper" --config "$MAPPER_CONFIG" --pose-source tracker \
    --output-dir "$WORK" --lcm-url "$url" > mapper.log 2>&1 &
  mapper=$!
  "$CBLOX_BIN/cblox-tracker" --config "$TRACKER_CONFIG" --initial-pose-from-gt \
    --lcm-url "$url" > tracker.log 2>&1 &
  tracker=$!
  sleep 2  # both subscribed, vocabulary loaded
  clk=$(getconf CLK_TCK)
  sample() {  # time tracker_cpu_s tracker_rss_kib mapper_cpu_s mapper_rss_kib
    local line="$(date +%s.%N)"
    for p in $tracker $mapper; do
      if [[ -r /proc/$p/stat ]]; then
        local f=($(sed "s/^.*) //" /proc/$p/stat))
        local rss=$(awk "/^VmRSS/ {print \$2}" /proc/$p/status)
        line+=" $(( f[11] + f[12] )) $rss"
      else
        line+=" nan nan"
      fi
    done
    echo "$line $clk"
  }
  sample > samples.txt
  lcm-logplayer --lcm-url="$url" "$LOG" > logplayer.log 2>&1 &
  player=$!
  while kill -0 $player 2> /dev/null; do sleep 1; sample >> samples.txt; done
  wait $player; echo $? > logplayer.status
  sample >> samples.txt
  sleep 3
  sample >> samples.txt
  threads() {  # one line per live thread: name, CPU ticks since it started; then the process
    for t in /proc/$1/task/*; do
      local f=($(sed "s/^.*) //" $t/stat))
      echo "$(tr " " "_" < $t/comm) $(( f[11] + f[12] ))"
    done
    local f=($(sed "s/^.*) //" /proc/$1/stat))
    echo "(process) $(( f[11] + f[12] ))"
  }
  threads $tracker > threads_tracker.txt
  threads $mapper > threads_mapper.txt
  for p in $tracker $mapper; do awk "/^VmHWM/ {print \$2}" /proc/$p/status; done > hwm.txt
  kill -TERM $tracker $mapper
  wait $tracker; echo $? > tracker.status
  wait $mapper; echo $? > mapper.status
'
rc=0
/usr/bin/env python3 - "$work" "$out" "$scene" "$trajectory" "$laps" "$tracker_config" \
  "$mapper_config" << 'PY' || rc=$?
import os, re, sys
work, out, scene, trajectory, laps, tracker_config, mapper_config = sys.argv[1:8]
rows = [l.split() for l in open(f"{work}/samples.txt") if l.strip()]
clk = float(rows[0][5])
def series(col):
    pts = []
    for r in rows:
        if r[col] == "nan":
            continue
        pts.append((float(r[0]), float(r[col]) / clk))
    return pts
t0, t1 = float(rows[0][0]), float(rows[-2][0])  # the replay: first sample to the player's end
def share(pts):
    inside = [p for p in pts if t0 <= p[0] <= t1]
    return (inside[-1][1] - inside[0][1]) / (inside[-1][0] - inside[0][0])
def window_max(pts, width=10.0):  # "-" when the replay is shorter than one window
    best = None
    for i, (ti, ci) in enumerate(pts):
        for tj, cj in pts[i + 1:]:
            if tj - ti >= width:
                rate = (cj - ci) / (tj - ti)
                best = rate if best is None else max(best, rate)
                break
    return "-" if best is None else f"{best:.2f}"
tracker, mapper = series(1), series(3)
both = [(a[0], a[1] + b[1]) for a, b in zip(tracker, mapper)]
hwm = [int(x) / 1024 for x in open(f"{work}/hwm.txt").read().split()]
status = {n: int(open(f"{work}/{n}.status").read()) for n in ("tracker", "mapper", "logplayer")}
def last(pattern, name):
    lines = [l for l in open(f"{work}/{name}.log") if "stopped:" in l]
    m = re.search(pattern, lines[-1]) if lines else None
    return m.groups() if m else None
tr = last(r"stopped: (\d+) frames .*?: (\d+) tracked, (\d+) lost, (\d+) relocalized, (\d+) dropped, (\d+) rejected; (\d+) keyframes.*?(\d+) loops; tracking median ([\d.]+) ms, frame median ([\d.]+) ms p95 ([\d.]+) ms", "tracker")
mp = last(r"stopped: (\d+) frames integrated .*?, (\d+) dropped, (\d+) rejected, (\d+) subvolumes.*?integration median ([\d.]+) ms p99 ([\d.]+) ms", "mapper")
wall = t1 - t0
lines = [
    f"`scripts/bench_pipeline_replay.sh --scene {scene} --trajectory {trajectory} --laps {laps}`"
    f" (tracker config {os.path.basename(tracker_config)}, mapper config {os.path.basename(mapper_config)}): "
    f"the log played in real time for {wall:.0f} s into the shipped tracker + mapper"
    + (f" ({int(tr[0])} frames, {int(tr[0]) / wall:.1f} Hz)." if tr else "."),
    "",
    "| process | CPU (cores, whole replay) | CPU (max over 10 s) | peak RSS | frames |",
    "|---|---|---|---|---|",
]
if tr:
    lines.append(f"| cblox-tracker | {share(tracker):.2f} | {window_max(tracker)} | {hwm[0]:.0f} MiB | "
                 f"{tr[0]} processed, {tr[1]} tracked, {tr[2]} lost, {tr[4]} dropped, {tr[5]} rejected; "
                 f"{tr[6]} keyframes, {tr[7]} loops; frame median {tr[9]} ms, p95 {tr[10]} ms |")
if mp:
    lines.append(f"| cblox-mapper | {share(mapper):.2f} | {window_max(mapper)} | {hwm[1]:.0f} MiB | "
                 f"{mp[0]} integrated, {mp[1]} dropped, {mp[2]} rejected; {mp[3]} subvolumes; "
                 f"integration median {mp[4]} ms, p99 {mp[5]} ms |")
lines.append(f"| tracker + mapper | **{share(both):.2f}** | {window_max(both)} | {sum(hwm):.0f} MiB | |")
lines.append("")
# Per thread (cblox names its threads cblox-<job>; others keep the process's name): CPU
# seconds since each started (the 2 s before the replay included), over the replay's wall
# time; "ended" is what threads that ended before the end took (the global BA's).
for proc in ("tracker", "mapper"):
    try:
        rows_t = [l.split() for l in open(f"{work}/threads_{proc}.txt") if l.strip()]
    except OSError:
        continue
    total = next(float(v) for n, v in rows_t if n == "(process)") / clk
    by_name = {}
    for n, v in rows_t:
        if n != "(process)":
            by_name[n] = by_name.get(n, 0.0) + float(v) / clk
    ended = total - sum(by_name.values())
    parts = [f"{n} {c / wall:.2f}" for n, c in sorted(by_name.items(), key=lambda x: -x[1]) if c / wall >= 0.005]
    if ended / wall >= 0.005:
        parts.append(f"ended {ended / wall:.2f}")
    lines.append(f"cblox-{proc} by thread (cores): " + ", ".join(parts) + ".")
lines.append("")
lines.append(f"Exit status: tracker {status['tracker']}, mapper {status['mapper']}, "
             f"lcm-logplayer {status['logplayer']}.")
text = "\n".join(lines)
print(text)
open(f"{out}/pipeline_{scene}.md", "w").write(text + "\n")
# Cores over time (per 2-sample step), an SVG a person can open.
W, H, pad = 800, 300, 40
def steps(pts):
    return [((a[0] + b[0]) / 2 - t0, (b[1] - a[1]) / (b[0] - a[0])) for a, b in zip(pts, pts[1:]) if b[0] > a[0]]
curves = {"tracker": steps(tracker), "mapper": steps(mapper), "tracker + mapper": steps(both)}
tmax = max(t1 - t0, 1.0)
ymax = max(2.0, max((c for s in curves.values() for _, c in s), default=1.0))
colors = {"tracker": "#1f77b4", "mapper": "#ff7f0e", "tracker + mapper": "#2ca02c"}
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{pad}" y="16">{scene}: CPU (cores) while the log plays at 20 Hz</text>']
for y in range(0, int(ymax) + 1):
    py = H - pad - y / ymax * (H - 2 * pad)
    svg.append(f'<line x1="{pad}" y1="{py:.1f}" x2="{W - pad}" y2="{py:.1f}" stroke="#ddd"/>')
    svg.append(f'<text x="4" y="{py + 4:.1f}">{y}</text>')
for k, (name, pts) in enumerate(curves.items()):
    path = " ".join(f"{pad + t / tmax * (W - 2 * pad):.1f},{H - pad - c / ymax * (H - 2 * pad):.1f}" for t, c in pts)
    svg.append(f'<polyline fill="none" stroke="{colors[name]}" stroke-width="1.5" points="{path}"/>')
    svg.append(f'<text x="{W - 200}" y="{30 + 14 * k}" fill="{colors[name]}">{name}</text>')
svg.append(f'<text x="{W / 2 - 20}" y="{H - 8}">seconds</text></svg>')
open(f"{out}/pipeline_{scene}_cpu.svg", "w").write("\n".join(svg))
sys.exit(0 if all(v == 0 for v in (status["tracker"], status["mapper"])) else 1)
PY
if [[ $recorded == 1 && $keep == 0 ]]; then rm -f "$log"; fi
exit $rc
