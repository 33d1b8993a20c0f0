#!/usr/bin/env bash
# A restarted capture (run inside a private network namespace, scripts/netns-run.sh):
# cblox-capture plays the simulated room into cblox-tracker + cblox-mapper, stops, and plays
# it again from the start (its time stamps go back by the length of the first run). The
# tracker must start a new map (map epoch 1) instead of rejecting every frame as out of
# order, and the mapper must keep the first run's subvolumes and integrate the second run's
# frames into new ones (keyed by epoch, so the tracker's repeated keyframe ids are new keys).
# Then a second cblox-mapper joins the bus: both say so in their logs, nothing is lost.
# Usage: run_restart_test.sh BIN_DIR WORK_DIR
set -euo pipefail
bin=$1
work=$2
repo=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$work"
mkdir -p "$work"
cd "$work"
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
frames=80
fail() { echo "FAIL: $*" >&2; exit 1; }
"$bin/cblox-mapper" --config "$repo/config/mapper.yaml" --pose-source tracker --output-dir "$work" \
  --lcm-url "$url" --quiet > mapper.log 2>&1 &
mapper=$!
"$bin/cblox-tracker" --config "$repo/config/tracker.yaml" --initial-pose-from-gt --lcm-url "$url" \
  --quiet > tracker.log 2>&1 &
tracker=$!
trap 'kill -KILL $mapper $tracker 2> /dev/null || true' EXIT
sleep 1

value() {  # value KEY: from a fresh `cblox-ctl status`
  "$bin/cblox-ctl" --lcm-url "$url" --timeout 20 status > status.txt || fail "no status reply"
  awk -v k="$1:" '$1 == k {print $2; exit}' status.txt
}
run_capture() {
  "$bin/cblox-capture" --source sim:room --trajectory orbit --frames "$frames" --rate 20 \
    --lcm-url "$url" --quiet > "capture_$1.log" 2>&1 || fail "cblox-capture ($1): $(cat "capture_$1.log")"
  sleep 2  # the last frames
}

run_capture first
integrated1=$(value frames_integrated)
subvolumes1=$(value subvolumes)
echo "first run: $integrated1 frames integrated, $subvolumes1 subvolumes"
(( integrated1 >= frames / 2 )) || fail "first run integrated only $integrated1 of $frames frames"

run_capture second
integrated2=$(value frames_integrated)
subvolumes2=$(value subvolumes)
restarts=$(value source_restarts)
echo "after the restart: $integrated2 frames integrated, $subvolumes2 subvolumes, $restarts source restarts"
cat status.txt
grep -q "map epoch 1 begins" tracker.log || fail "the tracker did not start map epoch 1: $(tail -5 tracker.log)"
(( integrated2 - integrated1 >= frames / 2 )) \
  || fail "integration did not resume: $((integrated2 - integrated1)) of $frames frames after the restart"
(( subvolumes2 > subvolumes1 )) || fail "no new subvolume after the restart ($subvolumes1 -> $subvolumes2)"
(( restarts >= 1 )) || fail "the mapper counted no source restart"

# A second mapper on the same bus: the first one says so (and keeps its map), the second too.
"$bin/cblox-mapper" --config "$repo/config/mapper.yaml" --pose-source tracker \
  --output-dir "$work/second" --lcm-url "$url" --quiet > second.log 2>&1 &
second=$!
sleep 3
kill -TERM $second
wait $second || fail "the second cblox-mapper exited with $?"
grep -q "another cblox-mapper (pid $second) is on this bus" mapper.log \
  || fail "the first mapper did not notice the second: $(tail -3 mapper.log)"
grep -q "another cblox-mapper (pid $mapper) is on this bus" second.log \
  || fail "the second mapper did not notice the first: $(tail -3 second.log)"
(( $(value frames_integrated) == integrated2 )) || fail "the second mapper changed the first's map"

kill -TERM $mapper $tracker
wait $mapper || fail "cblox-mapper exited with $?"
wait $tracker || fail "cblox-tracker exited with $?"
trap - EXIT
echo PASS
