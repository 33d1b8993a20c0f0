#!/usr/bin/env bash
# Crash test (issue "Reliability"): kill -9 of a checkpointing process at random moments, then
# a restart that must resume from its checkpoint with nothing acknowledged lost.
#
# cblox-capture (the built-in simulator, room, orbit, 20 Hz), cblox-tracker and cblox-mapper
# (tracker poses, small subvolumes so that fusions are frequent, checkpoint.period_s short) run
# in a private network namespace (scripts/netns-run.sh). The victim (--victims mapper, the
# default, or tracker; each has its victim_<name>_* functions below) is killed with SIGKILL
# N times. The mapper's kills cycle through three targeted moments:
#   integration  a random delay (0.3-2 s) while frames are integrated;
#   fusion       just after the mapper logs "fusion accepted" (the worker is fusing);
#   checkpoint   just after a new file appears in checkpoint.dir (a checkpoint is being
#                written). CBLOX_TEST_CHECKPOINT_PAUSE_MS (set here to --pause-ms) makes the
#                mapper sleep before each submap file and before the manifest of a checkpoint,
#                so the window is wide (test only; see README "Crash test").
# What was really happening is decided afterwards from evidence, not from the target: files of
# a generation above the committed manifest's (an interrupted checkpoint), a fusion accepted
# and not finished in the victim's log, else integration.
#
# "Acknowledged": the mapper reports a committed checkpoint generation G (status reply,
# checkpoint_generation; set only after the manifest's rename and the directory's fsync).
# The harness polls it; when it sees a new G it reads the manifest (cblox-map-verify
# --manifest-only) and, when that manifest's generation is G, records its listing (submap id,
# generation, file XXH64, anchor keyframe) as the acknowledged state. After each kill:
#   1. cblox-map-verify checkpoint.dir must pass (every checksum; the map as loaded re-encodes
#      to the files' XXH64) with a generation M >= G;
#   2. every acknowledged submap is present with identical (id, generation, XXH64), or was
#      superseded by a later committed generation (a newer file for the id, or the id is gone
#      and its anchor keyframe is in another submap's keyframes: a fusion M records); anything
#      else is LOST;
#   3. the restarted mapper must say "resumed from <dir> generation M" (not a half-written one);
#   4. with capture and tracker paused (SIGSTOP: nothing can change the map), the mapper saves
#      its loaded map (cblox-ctl save-map) and every submap file of it must have the XXH64 of
#      the checkpoint's: the map in memory is bit-identical to what was acknowledged.
# The tracker (--victims tracker: its checkpoints every --period into checkpoint.dir, the
# calibration file given so that a resumed map is restored at start) is killed while it
# tracks (a random moment) or while it writes a checkpoint (just after a new file appears;
# CBLOX_TEST_CHECKPOINT_PAUSE_MS widens the window the same way). Acknowledged = the
# generation G in its heartbeat (cblox-ctl status --all: set after the index's rename and the
# directory fsync) and the index then read (cblox-map-verify) having generation G. After each
# kill: the checkpoint verifies; every acknowledged keyframe is there with the same features
# digest (or culled by a later committed generation); the id lease covers every keyframe id
# acknowledged; the restart resumes exactly the newest committed generation and restores it;
# its first checkpoint, written with the capture paused, holds the same map bit for bit (every
# keyframe's state and features digests, the landmarks' digest); and the mapper, which runs
# throughout, never saw a keyframe id twice (keyframe_duplicate stays 0).
# Writes a markdown section to --report (default /tmp/reliability/crash_<victim>.md).
# Exit status: 0 all checks passed (and, with 9 kills or more, all three moments were hit),
# 1 a check failed, 2 usage or set-up error.
#
# The sparse map stops growing once the room is known: no keyframes, no new subvolumes, no
# fusions. So every --epoch-kills kills (5) the capture restarts (the tracker begins a new map
# epoch and makes keyframes again), and every --mission-kills kills (20) everything starts
# afresh with a new checkpoint directory (the map stays small, and so does each check).
#
# Usage: scripts/crash_test.sh [--kills N] [--seed S] [--period S] [--pause-ms MS]
#                              [--mission-kills N] [--epoch-kills N]
#                              [--work DIR] [--report FILE] [--victims mapper|tracker]
# BUILD_DIR selects the build (default build).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
kills=200 seed="" period=1.0 pause_ms=40 mission_kills=20 epoch_kills=5
work=/tmp/reliability/crash_work
report="" victims=mapper
args=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --kills) kills=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --period) period=$2; shift 2 ;;
    --pause-ms) pause_ms=$2; shift 2 ;;
    --mission-kills) mission_kills=$2; shift 2 ;;
    --epoch-kills) epoch_kills=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --report) report=$2; shift 2 ;;
    --victims) victims=$2; shift 2 ;;
    *) echo "crash_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[[ $kills =~ ^[0-9]+$ && $kills -ge 1 ]] || { echo "crash_test: --kills must be >= 1" >&2; exit 2; }
[[ $victims == mapper || $victims == tracker ]] \
  || { echo "crash_test: --victims must be mapper or tracker" >&2; exit 2; }
victim=$victims
report=${report:-/tmp/reliability/crash_$victim.md}
if [[ "${CBLOX_IN_NETNS:-}" != "1" ]]; then
  CBLOX_IN_NETNS=1 exec "$repo/scripts/netns-run.sh" "$repo/scripts/crash_test.sh" "${args[@]}"
fi
seed=${seed:-$(( $(date +%s) % 100000 ))}
RANDOM=$seed
build=${BUILD_DIR:-build}
[[ $build == /* ]] || build=$repo/$build
bin=$(cd "$build/daemon" && pwd)
for exe in cblox-capture cblox-tracker cblox-mapper cblox-ctl cblox-map-verify; do
  [[ -x $bin/$exe ]] || { echo "crash_test: $bin/$exe missing (build it)" >&2; exit 2; }
done
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
rm -rf "$work"
mkdir -p "$work" "$(dirname "$report")"
cd "$work"
results=$work/results.tsv  # one row per kill
: > "$results"
problems=$work/problems.txt
: > "$problems"
now_ms() { local t=${EPOCHREALTIME/./}; echo $(( t / 1000 )); }
rand_ms() { echo $(( $1 + RANDOM % ($2 - $1 + 1) )); }  # uniform in [$1, $2]
sleep_ms() { sleep "$(printf '%d.%03d' $(( $1 / 1000 )) $(( $1 % 1000 )))"; }
problem() { echo "PROBLEM (kill $k): $*" | tee -a "$problems" >&2; }
ctl() { "$bin/cblox-ctl" --lcm-url "$url" --timeout "${CTL_TIMEOUT:-3}" "$@"; }
# record_ack G [VERIFY ARGS...]: the victim reported committed generation G; reads the checkpoint
# (cblox-map-verify --json) and, when it is generation G, keeps it as the acknowledged state
# (ack.json). A newer generation committed meanwhile is acknowledged by the next poll.
record_ack() {
  local g=$1 m
  shift
  "$bin/cblox-map-verify" "$ckpt" "$@" --json > "$work/ack_try.json" 2> /dev/null || {
    problem "generation $g acknowledged, but the checkpoint in $ckpt does not verify"
    return 0
  }
  m=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["generation"])' \
    "$work/ack_try.json")
  if (( m < g )); then
    problem "generation $g acknowledged, but the checkpoint in $ckpt is generation $m"
  elif (( m == g )); then
    mv "$work/ack_try.json" "$work/ack.json"
    ack_gen=$g
  fi
}
# True while a checkpoint generation is being written: a subvolume file or a temporary
# file newer than the manifest (the evidence victim_mapper_check counts as a write).
checkpoint_writing() {
  [[ -f $ckpt/$manifest ]] || return 1
  [[ -n $(find "$ckpt" -maxdepth 1 \( -name 'submap_*' -o -name '*.tmp.*' \) \
            -newer "$ckpt/$manifest" -print -quit 2> /dev/null) ]]
}

# wait_for_new_file GLOB: returns when a file matching GLOB appears in the checkpoint directory
# that was not there when it was called (a checkpoint is being written), or after 8 s.
wait_for_new_file() {
  local f found=0 deadline=$(( $(now_ms) + 8000 ))
  declare -A seen=()
  for f in "$ckpt"/*; do seen[$f]=1; done
  while (( ! found && $(now_ms) < deadline )); do
    for f in "$ckpt"/$1; do
      [[ -e $f && -z ${seen[$f]:-} ]] && { found=1; break; }
    done
    (( found )) || sleep 0.005
  done
}
# value KEY FILE: from `cblox-ctl status` output ("  key: value").
value() { awk -v k="$1:" '$1 == k {print $2; exit}' "$2"; }

# ---------------------------------------------------------------------------------------------
# The pipeline around the victim: capture and tracker run for the whole test.

capture_pid="" tracker_pid="" mapper_pid=""
start_capture() {
  "$bin/cblox-capture" --source sim:room --trajectory orbit --laps 1000 --rate 20 \
    --lcm-url "$url" --quiet >> capture.log 2>&1 &
  capture_pid=$!
}
start_tracker() {
  "$bin/cblox-tracker" --config "$repo/config/tracker.yaml" --initial-pose-from-gt \
    --lcm-url "$url" --quiet > tracker.log 2>&1 &
  tracker_pid=$!
}
# The mapper when it is not the victim: tracker poses, shipped settings, no checkpoints.
start_plain_mapper() {
  "$bin/cblox-mapper" --config "$repo/config/mapper.yaml" --pose-source tracker \
    --output-dir "$work/mapper_out" --lcm-url "$url" --quiet > mapper.log 2>&1 &
  mapper_pid=$!
}
pause_inputs() {
  kill -STOP "$capture_pid" 2> /dev/null || true
  [[ $victim == mapper ]] && kill -STOP "$tracker_pid" 2> /dev/null
  return 0
}
resume_inputs() {
  kill -CONT "$tracker_pid" "$capture_pid" 2> /dev/null || true
  # The simulator's trajectory is long, but should it end: a new run (a new map epoch).
  kill -0 "$capture_pid" 2> /dev/null || start_capture
}

# ---------------------------------------------------------------------------------------------
# Victim: cblox-mapper. victim_mapper_start / _ack / _arm PHASE / _kill / _check.

ckpt="" mission=0
manifest=manifest.cbmap
mapper_pid="" mapper_log="" run=0
ack_gen=0            # generation of the acknowledged state (ack.json)
last_ack_check_ms=0
write_mapper_config() {
  cat > mapper.yaml <<EOF
pose_source: tracker
output_dir: $work/mapper_out
subvolumes:
  max_keyframes_per_subvolume: 2   # many subvolumes, many fusions
maintenance:
  min_shared_landmarks: 10
  min_shared_ratio: 0.02
  q_min: 100.0
  retry_after_s: 1.0
  max_retry_after_s: 4.0
fusion:
  num_threads: 1
worker:
  sched_idle: false                # the VM is shared: SCHED_IDLE would starve fusions
checkpoint:
  dir: $ckpt
  period_s: $period
  resume: true
EOF
}

victim_mapper_start() {
  run=$((run + 1))
  mapper_log=$work/mapper_$run.log
  CBLOX_TEST_CHECKPOINT_PAUSE_MS=$pause_ms "$bin/cblox-mapper" --config mapper.yaml \
    --lcm-url "$url" > "$mapper_log" 2>&1 &
  mapper_pid=$!
  local deadline=$(( $(now_ms) + 20000 ))
  until CTL_TIMEOUT=0.3 ctl status > "$work/status.txt" 2> /dev/null; do
    if ! kill -0 "$mapper_pid" 2> /dev/null; then
      problem "cblox-mapper exited at start: $(tail -3 "$mapper_log")"
      return 1
    fi
    (( $(now_ms) < deadline )) || { problem "cblox-mapper does not answer status"; return 1; }
  done
}

# Records the acknowledged state when the mapper reports a newer committed generation.
victim_mapper_ack() {
  last_ack_check_ms=$(now_ms)
  ctl status > "$work/status.txt" 2> /dev/null || return 0
  local g
  g=$(value checkpoint_generation "$work/status.txt")
  [[ -n $g ]] && (( g > ack_gen )) || return 0
  record_ack "$g" --manifest-only
}
ack_if_due() { (( $(now_ms) - last_ack_check_ms >= 400 )) && victim_mapper_ack; return 0; }

# Returns when it is time to kill for PHASE (integration | fusion | checkpoint).
victim_mapper_arm() {
  local phase=$1 start
  start=$(now_ms)
  # At least one acknowledged checkpoint of this run first (or 6 s).
  local acked_before=$ack_gen
  while (( ack_gen == acked_before && $(now_ms) - start < 6000 )); do
    victim_mapper_ack
    sleep 0.2
  done
  case $phase in
    integration)
      # A random moment, then just after a checkpoint commits while no fusion is pending
      # (the worker is idle then; the integrator works all the time); at most 10 s.
      local until_ms=$(( $(now_ms) + $(rand_ms 300 1500) ))
      while (( $(now_ms) < until_ms )); do ack_if_due; sleep 0.05; done
      local inode deadline=$(( $(now_ms) + 10000 ))
      inode=$(stat -c %i "$ckpt/$manifest" 2> /dev/null || echo none)
      while (( $(now_ms) < deadline )); do
        if [[ $(stat -c %i "$ckpt/$manifest" 2> /dev/null || echo none) != "$inode" ]]; then
          inode=$(stat -c %i "$ckpt/$manifest" 2> /dev/null || echo none)
          (( $(grep -cE "fused subvolume|fusion of subvolume" "$mapper_log" || true) >=
             $(grep -c "fusion accepted" "$mapper_log" || true) )) && break
        fi
        sleep 0.01
      done
      sleep_ms "$(rand_ms 20 150)"
      ;;
    fusion)
      # Just after the mapper accepted a pair, while the fusion has not finished (re-armed
      # when it finished before the kill); at most 45 s (a loaded machine makes keyframes, and
      # so subvolumes to fuse, slowly: CI once saw no fusion accepted in three 30 s waits).
      # A checkpoint being written then would make the kill count as one during a write
      # (the evidence left behind decides), so the kill waits, while the fusion is still
      # pending, for no write to be under way (with the test's pause before each file, writes
      # fill most of the time when there are many subvolumes).
      local accepted done_ fired=0 deadline=$(( $(now_ms) + 45000 ))
      accepted=$(grep -c "fusion accepted" "$mapper_log" || true)
      while (( ! fired && $(now_ms) < deadline )); do
        if (( $(grep -c "fusion accepted" "$mapper_log" || true) > accepted )); then
          accepted=$(grep -c "fusion accepted" "$mapper_log" || true)
          sleep_ms "$(rand_ms 20 120)"
          while :; do
            done_=$(grep -cE "fused subvolume|fusion of subvolume" "$mapper_log" || true)
            (( done_ < accepted )) || break
            if ! checkpoint_writing; then fired=1; break; fi
            sleep 0.005
          done
          continue
        fi
        ack_if_due
        sleep 0.02
      done
      ;;
    checkpoint)
      # Just after a file of a new generation appeared, before its manifest commits; re-armed
      # (up to 5 times) when the manifest was replaced before the kill, as happens when this
      # script is starved of CPU on a loaded machine.
      local tries inode
      for (( tries = 0; tries < 5; tries++ )); do
        ack_if_due
        inode=$(stat -c %i "$ckpt/$manifest" 2> /dev/null || echo none)
        wait_for_new_file "submap_*"
        sleep_ms "$(rand_ms 0 "$pause_ms")"
        [[ $(stat -c %i "$ckpt/$manifest" 2> /dev/null || echo none) == "$inode" ]] && break
      done
      : # killed now even after 5 misses (the phase is decided by the evidence)
      ;;
  esac
}

victim_mapper_kill() {
  kill -KILL "$mapper_pid" 2> /dev/null || true
  wait "$mapper_pid" 2> /dev/null || true
}

# After the kill: the checks (see the top of this file). Appends one row to $results.
victim_mapper_check() {
  local target=$1
  pause_inputs
  local verified=$work/verified.json
  local verify_ok=1
  if ! "$bin/cblox-map-verify" "$ckpt" --json > "$verified" 2> "$work/verify.err"; then
    verify_ok=0
    problem "checkpoint does not verify: $(cat "$work/verify.err")"
  fi
  [[ -f $work/ack.json ]] || echo '{"generation": 0, "submaps": []}' > "$work/ack.json"
  # Compare the acknowledged state with what is committed now; what was the victim doing?
  local line
  line=$(python3 - "$work/ack.json" "$verified" "$mapper_log" <<'PY'
import json, re, sys
ack = json.load(open(sys.argv[1]))
try:
    cur = json.load(open(sys.argv[2]))
except Exception:
    cur = {"generation": -1, "submaps": [], "unlisted_files": []}
M = cur.get("generation", -1)
by_id = {s["id"]: s for s in cur.get("submaps", [])}
keyframes = set(k for s in cur.get("submaps", []) for k in s["keyframes"])
identical = superseded = fused = lost = 0
details = []
for s in ack["submaps"]:
    c = by_id.get(s["id"])
    if c is not None and c["generation"] == s["generation"]:
        if c["xxh64"] == s["xxh64"] and c["file"] == s["file"]:
            identical += 1
        else:
            lost += 1
            details.append("submap %d g%d: same generation, other bytes" % (s["id"], s["generation"]))
    elif c is not None and c["generation"] > s["generation"] and M > ack["generation"]:
        superseded += 1
    elif c is None and M > ack["generation"] and s["anchor_keyframe"] in keyframes:
        fused += 1
    else:
        lost += 1
        details.append("submap %d g%d (file %s) not in generation %d" %
                       (s["id"], s["generation"], s["file"], M))
if M < ack["generation"]:
    details.append("committed generation %d is older than the acknowledged %d" % (M, ack["generation"]))
    lost += max(1, len(ack["submaps"]))
# Evidence of an interrupted checkpoint: files of a generation above the manifest's.
interrupted = 0
for name in cur.get("unlisted_files", []):
    m = re.match(r"submap_\d+_g(\d+)\.cbsub", name)
    if (m and int(m.group(1)) > M) or ".tmp." in name:
        interrupted = 1
# A fusion accepted and not finished when the victim died.
pending = {}
for text in open(sys.argv[3], errors="replace"):
    a = re.search(r"fusion accepted: subvolume (\d+) into (\d+)", text)
    if a:
        pending[a.groups()] = True
    d = re.search(r"fus(?:ed|ion of) subvolume (\d+) into (\d+)", text)
    if d:
        pending.pop(d.groups(), None)
phase = "checkpoint_write" if interrupted else ("fusion" if pending else "integration")
print(phase, M, ack["generation"], len(ack["submaps"]), identical, superseded, fused, lost,
      "; ".join(details) or "-")
PY
)
  local phase m g n identical superseded fused lost details
  read -r phase m g n identical superseded fused lost details <<< "$line"
  (( lost == 0 )) || problem "acknowledged generation $g: $lost submap(s) lost: $details"

  # Restart: it must resume exactly generation M, and hold exactly its voxels.
  local resumed_ok=0 memory_ok=0
  if victim_mapper_start; then
    local said
    said=$(grep -o "resumed from $ckpt generation [0-9]*" "$mapper_log" | awk '{print $NF}' || true)
    if [[ $said == "$m" ]]; then
      resumed_ok=1
    else
      problem "restart resumed generation '${said:-none}', the newest committed is $m"
    fi
    local saved=resumed_$k
    if CTL_TIMEOUT=30 ctl save-map "$saved" > "$work/save.txt" 2>&1 &&
      "$bin/cblox-map-verify" "$work/mapper_out/$saved" --json > "$work/saved.json" 2> /dev/null; then
      if python3 - "$verified" "$work/saved.json" <<'PY'
import json, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
key = lambda m: sorted((s["id"], s["xxh64"], s["blocks"], s["finished"]) for s in m["submaps"])
sys.exit(0 if key(a) == key(b) and b["counters"].get("subvolumes_fused", 0) == 0 else 1)
PY
      then
        memory_ok=1
      else
        problem "the resumed map differs from checkpoint generation $m"
      fi
    else
      problem "save-map of the resumed map failed: $(tail -2 "$work/save.txt")"
    fi
    rm -rf "${work:?}/mapper_out/$saved"
  fi
  resume_inputs
  # The restarted mapper said it resumed generation M: that is acknowledged now. Its own
  # checkpoint_generation starts at 0 until its first checkpoint (above M).
  cp "$verified" "$work/ack.json" 2> /dev/null || true
  ack_gen=0
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$k" "$target" "$phase" "$m" \
    "$g" "$n" "$identical" "$superseded" "$fused" "$lost" "$verify_ok" "$resumed_ok" \
    "$memory_ok" >> "$results"
}

# ---------------------------------------------------------------------------------------------
# Victim: cblox-tracker. victim_tracker_start / _ack / _arm PHASE / _kill / _check.

tracker_log=""
write_tracker_config() {
  cat > tracker.yaml <<EOF2
checkpoint:
  dir: $ckpt
  period_s: $period
  resume: true
EOF2
}

victim_tracker_start() {
  run=$((run + 1))
  tracker_log=$work/tracker_$run.log
  CBLOX_TEST_CHECKPOINT_PAUSE_MS=$pause_ms "$bin/cblox-tracker" --config tracker.yaml \
    --initial-pose-from-gt --calibration "$repo/config/calibration/sim_rig.yaml" \
    --lcm-url "$url" > "$tracker_log" 2>&1 &
  tracker_pid=$!
  sleep 0.5
  kill -0 "$tracker_pid" 2> /dev/null || { problem "cblox-tracker exited at start: $(tail -3 "$tracker_log")"; return 1; }
}

# The generation the tracker's heartbeat acknowledges (0: none yet).
tracker_acked_generation() {
  ctl status --all --listen 1.1 --expect "" > "$work/status_all.txt" 2> /dev/null || true
  awk '$1 == "tracker" && $2 == "checkpoints:" {gsub(",", "", $4); print $4; exit}' \
    "$work/status_all.txt"
}

# Records the acknowledged state when the tracker reports a newer committed generation.
victim_tracker_ack() {
  last_ack_check_ms=$(now_ms)
  local g
  g=$(tracker_acked_generation)
  [[ -n $g ]] && (( g > ack_gen )) || return 0
  record_ack "$g"
}

# Returns when it is time to kill for PHASE (tracking | checkpoint).
victim_tracker_arm() {
  local phase=$1 start acked_before=$ack_gen
  start=$(now_ms)
  while (( ack_gen == acked_before && $(now_ms) - start < 8000 )); do victim_tracker_ack; done
  case $phase in
    tracking)
      sleep_ms "$(rand_ms 200 1500)"
      ;;
    checkpoint)
      wait_for_new_file "*"
      sleep_ms "$(rand_ms 0 "$pause_ms")"
      ;;
  esac
}

killed_pid=""
victim_tracker_kill() {
  killed_pid=$tracker_pid
  kill -KILL "$tracker_pid" 2> /dev/null || true
  wait "$tracker_pid" 2> /dev/null || true
}

# After the kill: the checks (see the top of this file). Appends one row to $results.
victim_tracker_check() {
  local target=$1
  pause_inputs
  local verified=$work/verified.json verify_ok=1
  if ! "$bin/cblox-map-verify" "$ckpt" --json > "$verified" 2> "$work/verify.err"; then
    verify_ok=0
    problem "tracker checkpoint does not verify: $(cat "$work/verify.err")"
  fi
  [[ -f $work/ack.json ]] || echo '{"generation": 0, "keyframes": []}' > "$work/ack.json"
  local line
  line=$(python3 - "$work/ack.json" "$verified" "$killed_pid" <<'PY'
import json, re, sys
ack = json.load(open(sys.argv[1]))
killed = sys.argv[3]
try:
    cur = json.load(open(sys.argv[2]))
except Exception:
    cur = {}
M = cur.get("generation", -1)
by_id = {k["id"]: k for k in cur.get("keyframes", [])}
acked = [k for k in ack.get("keyframes", []) if not k["bad"]]
identical = superseded = culled = lost = 0
details = []
# The source restarted since the acknowledgement (the harness restarts the capture every few
# kills): the tracker dropped that map for a new one in the next epoch, by design, and its
# checkpoint holds the new map. The old map's keyframes are superseded, not lost.
new_epoch = M > ack["generation"] and cur.get("map_epoch", -1) > ack.get("map_epoch", -1)
# The source restarted after the last checkpoint: ids of a newer epoch were published (the
# lease says so) but no checkpoint of that map committed. The restart must start a new map
# after that epoch; the acknowledged keyframes were superseded by the restart of the source.
lease = cur.get("lease") or {}
new_map = lease.get("map_epoch", -1) > cur.get("map_epoch", -1)
if new_epoch or new_map:
    superseded, acked = len(acked), []
for k in acked:
    c = by_id.get(k["id"])
    if c is not None and not c["bad"] and c["features_digest"] == k["features_digest"]:
        identical += 1
    elif c is not None and c["bad"] and M > ack["generation"]:
        culled += 1
    else:
        lost += 1
        details.append("keyframe %d not in generation %d with its features" % (k["id"], M))
if M < ack["generation"]:
    details.append("committed generation %d is older than the acknowledged %d" % (M, ack["generation"]))
    lost += max(1, len(acked))
top = max([k["id"] for k in ack.get("keyframes", [])], default=-1)
if acked and lease.get("map_epoch") == ack.get("map_epoch") and lease.get("keyframe_floor", 0) <= top:
    details.append("the id lease (%s) does not cover acknowledged keyframe %d" % (lease, top))
    lost += 1
# Evidence of an interrupted checkpoint: a temporary file of the killed process, or a chunk of
# a generation above the committed index's.
def newer_chunk(n):
    m = re.match(r"keyframes_e\d+_g(\d+)\.cbkf$", n)
    return bool(m) and int(m.group(1)) > M
interrupted = any((".tmp.%s." % killed) in n and not n.startswith("keyframe_ids.lease")
                  or newer_chunk(n) for n in cur.get("unlisted_files", []))
phase = "checkpoint_write" if interrupted else "tracking"
print(phase, M, ack["generation"], len(acked) + superseded, identical, superseded, culled, lost,
      cur.get("good_keyframes", 0), int(new_map),
      "; ".join(details) or "-")
PY
)
  local phase m g n identical superseded culled lost good new_map details
  read -r phase m g n identical superseded culled lost good new_map details <<< "$line"
  [[ -n $lost ]] || { problem "the checks could not run: $line"; lost=1; good=0 new_map=0; }
  (( lost == 0 )) || problem "acknowledged generation $g: $lost keyframe(s) lost: $details"

  # Restart: it must resume exactly generation M and restore it (the camera is configured),
  # and its first checkpoint, with nothing tracked since, must hold the same map.
  local resumed_ok=0 memory_ok=0
  if victim_tracker_start; then
    local deadline=$(( $(now_ms) + 20000 ))
    until grep -q "resumed map restored\|cannot be continued\|starting a new map" "$tracker_log"; do
      (( $(now_ms) < deadline )) || break
      sleep 0.1
    done
    local said restored
    said=$(grep -o "resuming the map of epoch [0-9]* in $ckpt (checkpoint [0-9]*" "$tracker_log" |
      awk '{print $NF}' || true)
    restored=$(grep -o "resumed map restored: [0-9]*" "$tracker_log" | awk '{print $NF}' || true)
    if (( new_map )); then
      # Nothing of the newer map was committed: the restart must start a new map, and there is
      # no restored map to compare.
      if grep -q "is behind the ids published.*starting a new map" "$tracker_log"; then
        resumed_ok=1 memory_ok=1
      else
        problem "ids of a newer epoch were published, but the restart did not start a new map: $(grep -i "resum\|map" "$tracker_log" | head -3)"
      fi
    elif [[ $said == "$m" && $restored == "$good" ]]; then
      resumed_ok=1
    else
      problem "restart resumed generation '${said:-none}' with '${restored:-no}' keyframes restored; the newest committed is $m with $good: $(grep -i "resum\|continued" "$tracker_log" | head -3)"
    fi
    deadline=$(( $(now_ms) + 15000 ))
    local next=$m
    (( new_map )) && deadline=0
    while (( next <= m && $(now_ms) < deadline )); do
      sleep 0.3
      "$bin/cblox-map-verify" "$ckpt" --json > "$work/after.json" 2> /dev/null || continue
      next=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["generation"])' \
        "$work/after.json")
    done
    if (( new_map )); then
      :
    elif (( next > m )) && python3 - "$verified" "$work/after.json" 2> "$work/differ.txt" <<'PY'
import json, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
n = len(a["keyframes"])
differ = [x["id"] for x, y in zip(a["keyframes"], b["keyframes"][:n])
          if x["state_digest"] != y["state_digest"] or x["features_digest"] != y["features_digest"]]
placeholders = all(y["bad"] and y["features"] == 0 for y in b["keyframes"][n:])
ok = (not differ and placeholders and a["landmarks_digest"] == b["landmarks_digest"] and
      b["next_landmark_id"] >= a["next_landmark_id"] and a["map_epoch"] == b["map_epoch"])
if not ok:
    print("keyframes differing: %s; placeholders ok: %s; landmarks %d -> %d (%s); next id %d -> %d"
          % (differ[:5], placeholders, a["landmarks"], b["landmarks"],
             "same" if a["landmarks_digest"] == b["landmarks_digest"] else "differ",
             a["next_landmark_id"], b["next_landmark_id"]), file=sys.stderr)
sys.exit(0 if ok else 1)
PY
    then
      memory_ok=1
    else
      problem "the resumed tracker's first checkpoint (generation $next) differs from generation $m: $(cat "$work/differ.txt")"
    fi
  fi
  ctl status > "$work/status.txt" 2> /dev/null || true
  local duplicates
  duplicates=$(value rejected_keyframe_duplicate "$work/status.txt")
  (( ${duplicates:-0} == 0 )) || problem "the mapper saw $duplicates repeated keyframe ids"
  resume_inputs
  cp "$verified" "$work/ack.json" 2> /dev/null || true
  ack_gen=0
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$k" "$target" "$phase" "$m" \
    "$g" "$n" "$identical" "$superseded" "$culled" "$lost" "$verify_ok" "$resumed_ok" \
    "$memory_ok" >> "$results"
}

# ---------------------------------------------------------------------------------------------
# The run

cleanup() {
  kill -CONT "$capture_pid" "$tracker_pid" 2> /dev/null || true
  kill -TERM "$mapper_pid" "$tracker_pid" "$capture_pid" 2> /dev/null || true
  wait 2> /dev/null || true
}
trap cleanup EXIT
# A mission: fresh capture, tracker and mapper (one of them the victim), a new checkpoint
# directory.
start_mission() {
  kill -KILL "$capture_pid" "$tracker_pid" "$mapper_pid" 2> /dev/null || true
  wait "$capture_pid" "$tracker_pid" "$mapper_pid" 2> /dev/null || true
  mission=$((mission + 1))
  ckpt=$work/${victim}_checkpoint_$mission
  rm -rf "$work/${victim}_checkpoint_$((mission - 1))" "$work/mapper_out"
  rm -f "$work/ack.json"
  ack_gen=0
  if [[ $victim == mapper ]]; then
    write_mapper_config
    start_tracker
    sleep 1
    start_capture
    victim_mapper_start
  else
    write_tracker_config
    start_plain_mapper
    victim_tracker_start || return 1
    sleep 1
    start_capture
  fi
}
# A new map epoch: the capture starts its trajectory again.
restart_capture() {
  kill -KILL "$capture_pid" 2> /dev/null || true
  wait "$capture_pid" 2> /dev/null || true
  start_capture
}
k=0
start_mission || exit 1
if [[ $victim == mapper ]]; then phases=(integration fusion checkpoint); else phases=(tracking checkpoint); fi
victim_pid() { if [[ $victim == mapper ]]; then echo "$mapper_pid"; else echo "$tracker_pid"; fi; }
begin_ms=$(now_ms)
echo "crash_test: $kills kills of cblox-$victim, seed $seed, checkpoint period $period s," \
  "pause $pause_ms ms; work dir $work"
for (( k = 1; k <= kills; k++ )); do
  target=${phases[$(( (k - 1) % ${#phases[@]} ))]}
  if (( k > 1 && (k - 1) % mission_kills == 0 )); then
    start_mission || break
  elif (( k > 1 && (k - 1) % epoch_kills == 0 )); then
    restart_capture
  fi
  "victim_${victim}_arm" "$target"
  "victim_${victim}_kill"
  "victim_${victim}_check" "$target"
  row=$(tail -1 "$results")
  IFS=$'\t' read -r _ _ phase m g n identical superseded fused lost _ _ _ <<< "$row"
  elapsed=$(( $(now_ms) - begin_ms ))
  rate=$(awk -v k="$k" -v ms="$elapsed" 'BEGIN {printf "%.1f", k * 60000 / ms}')
  eta=$(( elapsed * (kills - k) / k / 1000 ))
  unit=$([[ $victim == mapper ]] && echo "submaps" || echo "keyframes")
  printf 'kill %d/%d target %-11s happened during %-16s gen %s (acked %s: %s %s: %s same, %s newer, %s fused/culled, %s lost) %s kills/min ETA %dm%02ds\n' \
    "$k" "$kills" "$target" "$phase" "$m" "$g" "$n" "$unit" "$identical" "$superseded" "$fused" \
    "$lost" "$rate" $(( eta / 60 )) $(( eta % 60 ))
  kill -0 "$(victim_pid)" 2> /dev/null || { "victim_${victim}_start" || break; }
done
total_s=$(( ($(now_ms) - begin_ms) / 1000 ))

# ---------------------------------------------------------------------------------------------
# The report

cpu=$(awk -F': ' '/model name/ {print $2; exit}' /proc/cpuinfo)
commit=$(git -C "$repo" rev-parse --short HEAD 2> /dev/null || echo unknown)
python3 - "$results" "$problems" > "$report" <<PY
import collections, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
problems = [l.rstrip("\n") for l in open(sys.argv[2]) if l.strip()]
victim = "$victim"
if victim == "mapper":
    names = {"integration": "kill -9 during integration",
             "fusion": "kill -9 during a fusion (accepted, not finished: running or queued)",
             "checkpoint_write": "kill -9 during a checkpoint write (files of an uncommitted generation on disk)"}
else:
    names = {"tracking": "kill -9 while tracking (local mapping, loop closing running)",
             "checkpoint_write": "kill -9 during a checkpoint write (files of an uncommitted generation on disk)"}
agg = collections.OrderedDict((p, collections.Counter()) for p in names)
targeted = collections.Counter(r[1] for r in rows)
for r in rows:
    c = agg[r[2]]
    c["kills"] += 1
    for i, key in ((5, "acked"), (6, "same"), (7, "newer"), (8, "fused"), (9, "lost"),
                   (10, "verify"), (11, "resumed"), (12, "memory")):
        c[key] += int(r[i])
print("## Crash test: cblox-%s, kill -9 (scripts/crash_test.sh --victims %s)\n" % (victim, victim))
print("Machine: 2 vCPU AMD EPYC shared VM ($cpu, $(nproc) CPUs, shared with other builds and"
      " tests while it ran). Commit $commit, $(date -u +%Y-%m-%d).")
print("Rerun: \`scripts/crash_test.sh --victims $victim --kills $kills --seed $seed\` (period $period s, test pause"
      " $pause_ms ms before each checkpoint file; the capture restarts every $epoch_kills kills,"
      " a new mission with a fresh checkpoint directory every $mission_kills). $(( total_s / 60 )) min $(( total_s % 60 )) s for"
      " %d kills (%.1f s each: re-arm, kill, verify, restart, in-memory check)." %
      (len(rows), $total_s / max(1, len(rows))))
print()
if victim == "mapper":
    print("Pipeline: cblox-capture (simulator, room, orbit, 20 Hz) + cblox-tracker + cblox-mapper"
          " (tracker poses, 2 keyframes per subvolume, fusion thresholds lowered so that fusions are"
          " frequent, checkpoint.period_s $period) in a private network namespace. Targets cycle"
          " integration / fusion / checkpoint (%s); the table counts what was really happening,"
          " from evidence left behind." % ", ".join("%s %d" % kv for kv in sorted(targeted.items())))
    print()
    print("Acknowledged = the mapper reported checkpoint_generation G (set after the manifest's"
          " rename and the directory fsync) and the manifest then read had generation G; its"
          " listing (id, generation, file XXH64) is what must survive. After each kill: the"
          " checkpoint verifies (cblox-map-verify: every checksum, and the loaded voxels re-encode"
          " to the same XXH64), each acknowledged submap is identical or superseded by a later"
          " committed generation (newer file, or fused away as the newer manifest records), the"
          " restart resumes exactly the newest committed generation, and the map it holds in"
          " memory, saved with capture and tracker paused, has every submap's XXH64 of the"
          " checkpoint.")
else:
    print("Pipeline: cblox-capture (simulator, room, orbit, 20 Hz) + cblox-tracker (the victim:"
          " checkpoint.period_s $period, calibration file given) + cblox-mapper (tracker poses,"
          " shipped settings, never killed) in a private network namespace. Targets cycle"
          " tracking / checkpoint (%s); the table counts what was really happening, from evidence"
          " left behind." % ", ".join("%s %d" % kv for kv in sorted(targeted.items())))
    print()
    print("Acknowledged = the tracker's heartbeat said checkpoint_generation G (set after the"
          " index's rename and the directory fsync) and the index then read had generation G;"
          " its keyframes (id, features digest) are what must survive. After each kill: the"
          " checkpoint verifies (cblox-map-verify: every checksum, chunks, consistency), each"
          " acknowledged keyframe has the same features or was culled by a later committed"
          " generation, the id lease covers every acknowledged keyframe id, the restart resumes"
          " and restores exactly the newest committed generation, its first checkpoint (capture"
          " paused) has every keyframe's state and features digests and the landmarks' digest of"
          " that generation (bit-identical in memory), and the mapper saw no keyframe id twice.")
print()
unit = "submaps" if victim == "mapper" else "keyframes"
print("| fault injected | kills | acknowledged %s checked | identical | superseded by a %s | %s | lost | checkpoint verified | resumed newest committed generation | in-memory bit-identical |" % (unit, "newer file" if victim == "mapper" else "new map epoch (the capture restarted)", "fused away (recorded)" if victim == "mapper" else "culled later (recorded)"))
print("|---|---|---|---|---|---|---|---|---|---|")
tot = collections.Counter()
for p, c in agg.items():
    tot.update(c)
    print("| %s | %d | %d | %d | %d | %d | **%d** | %d/%d | %d/%d | %d/%d |" % (
        names[p], c["kills"], c["acked"], c["same"], c["newer"], c["fused"], c["lost"],
        c["verify"], c["kills"], c["resumed"], c["kills"], c["memory"], c["kills"]))
print("| **total** | %d | %d | %d | %d | %d | **%d** | %d/%d | %d/%d | %d/%d |" % (
    tot["kills"], tot["acked"], tot["same"], tot["newer"], tot["fused"], tot["lost"],
    tot["verify"], tot["kills"], tot["resumed"], tot["kills"], tot["memory"], tot["kills"]))
print()
if problems:
    print("Problems (%d):\n" % len(problems))
    for p in problems[:50]:
        print("- " + p)
else:
    print("Lost: nothing acknowledged. No problem found.")
PY
echo "crash_test: report in $report"
cat "$report"
[[ -s $problems ]] && { echo "crash_test: FAILED ($(wc -l < "$problems") problems)" >&2; exit 1; }
if (( kills >= 9 )); then
  expected_phases=(integration fusion checkpoint_write)
  [[ $victim == tracker ]] && expected_phases=(tracking checkpoint_write)
  for p in "${expected_phases[@]}"; do
    awk -F'\t' -v p="$p" '$3 == p {found = 1} END {exit !found}' "$results" \
      || { echo "crash_test: FAILED: no kill happened during $p" >&2; exit 1; }
  done
fi
echo "crash_test: PASS"
