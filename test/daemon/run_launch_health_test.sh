#!/usr/bin/env bash
# cblox-launch end to end, in a private network namespace (ctest runs it through
# scripts/netns-run.sh): capture (simulator, 5 Hz), tracker and mapper (tracker poses) under the
# launcher, with lcm-logger recording CBLOX_GT_POSE. Checks, with `cblox-ctl status --all`:
#  1. all three send heartbeats (exit 0), with the pids the launcher started;
#  2. after kill -9 of the tracker, the launcher says so and keeps running, capture and mapper
#     keep sending heartbeats, the tracker is "not heard" and cblox-ctl exits 4;
#  3. the mapper's heartbeat reports its pose input (CBLOX_FRAME_POSE) silent, and one log line
#     says so; after capture is stopped (SIGTERM) CBLOX_DEPTH too;
#  4. SIGINT to the launcher stops the rest, every exit code is reported, exit status 1 (the
#     tracker was killed), no process is left; log lines carry the process's name; the
#     recording holds CBLOX_GT_POSE only.
# Usage: run_launch_health_test.sh LAUNCHER BIN_DIR CONFIG_DIR WORK_DIR
set -uo pipefail
launcher_exe=$1 bin=$2 config=$3 work=$4
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
rm -rf "$work"
mkdir -p "$work"
log=$work/launch.log
ctl_out=$work/ctl.txt
started=$SECONDS

launcher=""
cleanup() {
  if [[ -n "$launcher" ]] && kill -0 "$launcher" 2> /dev/null; then
    kill -TERM "$launcher" 2> /dev/null
    for _ in $(seq 1 30); do kill -0 "$launcher" 2> /dev/null || break; sleep 0.5; done
    kill -KILL "$launcher" 2> /dev/null
  fi
  sed -n 's/^cblox-launch: started [a-z-]* (pid \([0-9]*\)).*/\1/p' "$log" 2> /dev/null |
    while read -r pid; do kill -KILL "$pid" 2> /dev/null; done
}
fail() {
  echo "FAIL ($((SECONDS - started)) s): $*"
  echo "--- last cblox-ctl output:"
  cat "$ctl_out" 2> /dev/null
  echo "--- launcher output:"
  cat "$log"
  cleanup
  exit 1
}
step() { echo "[$((SECONDS - started)) s] $*"; }
ctl() {  # ctl ARGS...: cblox-ctl status --all ARGS, output in $ctl_out, returns its status
  "$bin/cblox-ctl" --lcm-url "$url" status --all "$@" > "$ctl_out" 2>&1
}
pid_of() { sed -n "s/^cblox-launch: started $1 (pid \\([0-9]*\\)).*/\\1/p" "$log"; }
# wait_for SECONDS COMMAND...: retries COMMAND until it succeeds or SECONDS pass.
wait_for() {
  local deadline=$((SECONDS + $1))
  shift
  until "$@"; do
    ((SECONDS < deadline)) || return 1
    sleep 0.5
  done
}
row() { grep -E "^$1 " "$ctl_out"; }

step "starting cblox-launch"
"$launcher_exe" --bin-dir "$bin" --config-dir "$config" --lcm-url "$url" \
  --capture-args "--source sim:room --rate 5 --quiet" \
  --tracker-args "--vocabulary none --quiet" \
  --mapper-args "--pose-source tracker --output-dir $work/maps --quiet" \
  --record "$work/gt.lcmlog" --record-channels CBLOX_GT_POSE --stop-timeout 15 \
  > "$log" 2>&1 &
launcher=$!

# 1. All three alive.
wait_for 40 ctl --listen 2 || fail "capture, tracker and mapper not all heard within 40 s"
step "all three heard"
capture=$(pid_of capture) tracker=$(pid_of tracker) mapper=$(pid_of mapper)
logger=$(pid_of lcm-logger)
[[ -n "$capture" && -n "$tracker" && -n "$mapper" && -n "$logger" ]] ||
  fail "the launcher did not report the pids it started"
for name in capture tracker mapper; do
  pid=$(pid_of "$name")
  row "$name" | grep -qE "^$name +$pid " || fail "$name row without pid $pid"
done
grep -q "^alive: all expected processes (capture, tracker, mapper)" "$ctl_out" ||
  fail "no 'alive' line"

# 2. The tracker dies; the others keep running.
kill -KILL "$tracker"
died_line="cblox-launch: tracker (pid $tracker) ended: killed by signal 9 (KILL); still running: lcm-logger mapper capture"
wait_for 10 grep -qF "$died_line" "$log" || fail "the launcher did not report the tracker's death"
kill -0 "$launcher" 2> /dev/null || fail "the launcher exited when the tracker died"
for pid in "$capture" "$mapper"; do
  kill -0 "$pid" 2> /dev/null || fail "process $pid (capture or mapper) ended with the tracker"
done
ctl --listen 2
code=$?
((code == 4)) || fail "cblox-ctl status --all exited $code without the tracker (want 4)"
grep -q "^tracker  *-  not heard (no heartbeat in 2.0 s)" "$ctl_out" || fail "tracker not 'not heard'"
grep -q "^NOT ALIVE: tracker (expected: capture, tracker, mapper)" "$ctl_out" ||
  fail "no NOT ALIVE line"
row capture | grep -qE "^capture +$capture +[0-9.]+s " || fail "capture's heartbeats stopped"
row mapper | grep -qE "^mapper +$mapper +[0-9.]+s " || fail "mapper's heartbeats stopped"
step "tracker killed: reported, others alive, cblox-ctl exit 4"

# 3. Input silence: the mapper's poses stop with the tracker, its depth frames with capture.
# Only the poses: silent inputs are listed in the order watched (depth first), so a transient
# stall of depth frames on a loaded machine just means another try.
mapper_pose_silent() {
  ctl --listen 1.5 --expect capture,mapper &&
    row mapper | grep -qE "SILENT [0-9.]+s +input silent: CBLOX_FRAME_POSE for [0-9.]+ s; running"
}
wait_for 15 mapper_pose_silent || fail "the mapper does not report CBLOX_FRAME_POSE (alone) silent"
n=$(grep -c "^\[mapper\] cblox-mapper: input silent: nothing on CBLOX_FRAME_POSE for" "$log")
((n == 1)) || fail "$n log lines for the start of the CBLOX_FRAME_POSE silence (want 1)"
step "mapper: CBLOX_FRAME_POSE silent"

kill -TERM "$capture"
wait_for 15 grep -qF "cblox-launch: capture (pid $capture) ended: exit status 0; still running: lcm-logger mapper" "$log" ||
  fail "the launcher did not report capture's end"
mapper_depth_silent() {
  ctl --listen 1.5 --expect mapper && row mapper | grep -qE "CBLOX_DEPTH for [0-9.]+ s, CBLOX_FRAME_POSE for [0-9.]+ s; running"
}
wait_for 15 mapper_depth_silent || fail "the mapper does not report CBLOX_DEPTH silent after capture stopped"
grep -q "^\[mapper\] cblox-mapper: input silent: nothing on CBLOX_DEPTH for" "$log" ||
  fail "no log line for the CBLOX_DEPTH silence"
step "capture stopped: mapper reports CBLOX_DEPTH silent"

# 4. SIGINT stops the rest and reports every exit code.
kill -INT "$launcher"
for _ in $(seq 1 60); do kill -0 "$launcher" 2> /dev/null || break; sleep 0.5; done
kill -0 "$launcher" 2> /dev/null && fail "the launcher still runs 30 s after SIGINT"
wait "$launcher"
code=$?
launcher=""
((code == 1)) || fail "launcher exit status $code (want 1: the tracker was killed)"
for line in \
  "cblox-launch: stopping lcm-logger mapper: SIGTERM (SIGKILL after 15 s)" \
  "cblox-launch: lcm-logger (pid $logger): exit status 0" \
  "cblox-launch: mapper (pid $mapper): exit status 0" \
  "cblox-launch: tracker (pid $tracker): killed by signal 9 (KILL)" \
  "cblox-launch: capture (pid $capture): exit status 0" \
  "cblox-launch: exit status 1"; do
  grep -qxF "$line" "$log" || fail "missing line: $line"
done
for pid in "$capture" "$tracker" "$mapper" "$logger"; do
  kill -0 "$pid" 2> /dev/null && fail "process $pid still runs after the launcher exited"
done
# The summary comes after every process line, and nothing else is unprefixed.
[[ "$(tail -n 1 "$log")" == "cblox-launch: exit status 1" ]] || fail "the summary is not last"
for name in mapper tracker capture; do
  grep -q "^\[$name\] " "$log" || fail "no log line prefixed [$name]"
done
bad=$(grep -vcE '^(\[(capture|tracker|mapper|lcm-logger)\] |cblox-launch: )' "$log")
((bad == 0)) || fail "$bad lines neither prefixed nor the launcher's"
grep -qE ": line [0-9]+: +[0-9]+ Killed" "$log" && fail "bash's own 'Killed' notice reached the output"
# The recording: CBLOX_GT_POSE only.
[[ -s "$work/gt.lcmlog" ]] || fail "no recording"
grep -qa CBLOX_GT_POSE "$work/gt.lcmlog" || fail "no CBLOX_GT_POSE in the recording"
grep -qa CBLOX_STEREO "$work/gt.lcmlog" && fail "CBLOX_STEREO recorded (channels: CBLOX_GT_POSE)"
step "SIGINT: all stopped, exit codes reported, launcher exit status 1"
echo "PASS ($((SECONDS - started)) s)"
