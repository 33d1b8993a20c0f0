#!/usr/bin/env bash
# ctest lcm_spy.decodes_every_type: lcm-spy, started through scripts/lcm-spy.sh, decodes a
# message of every cblox LCM type.
#
# Usage: run_lcm_spy_test.sh SPY_SCRIPT TYPES_JAR PROBE_JAR PUBLISHER LCM_DIR OUT_DIR
#
# In a private network namespace (as scripts/netns-run.sh: loopback up, multicast routed on
# it, so nothing reaches or comes from the machine's network; and a private /tmp/.X11-unix,
# so its X server cannot touch the machine's) it starts Xvfb, then lcm-spy
# through SPY_SCRIPT on udpm://239.255.76.67:7667?ttl=0 with the cblox types jar, and
# PUBLISHER (publish_lcm_samples) sends the sample message of every top-level type on its
# cblox channel, repeatedly. A Java agent loaded into lcm-spy's JVM (PROBE_JAR, see
# lcm_spy_probe/LcmSpyProbe.java, passed in JDK_JAVA_OPTIONS, which the script keeps) reads
# back the channel table exactly as drawn (the text of each cell renderer of lcm-spy's
# JTable: no OCR), the classes of the objects lcm-spy decoded, and takes a screenshot of the
# window (OUT_DIR/lcm_spy.png). check_lcm_spy_table.py then requires every channel to show
# its type name with 0 undecodable messages and every cblox type (top-level and nested) to
# have been decoded. This fails when the jar lacks a type or has another version of it
# (lcm-spy then shows "?? <fingerprint>" and counts the messages as undecodable), when
# CLASSPATH or the JVM options of the script are wrong (no window or no types), or when a
# top-level type is missing from the publisher.
#
# Exit status 0 pass, 1 fail, 77 skip (Xvfb, Java, lcm-spy, the probe or network namespaces
# not available; the reason is printed).
set -euo pipefail

if [[ $# -lt 6 ]]; then
  echo "usage: $0 SPY_SCRIPT TYPES_JAR PROBE_JAR PUBLISHER LCM_DIR OUT_DIR" >&2
  exit 2
fi
in_netns=0
if [[ "$1" == "--in-netns" ]]; then
  in_netns=1
  shift
fi
spy=$1 jar=$2 probe=$3 publisher=$4 lcm_dir=$5 out_dir=$6
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

skip() {
  echo "SKIP lcm_spy.decodes_every_type: $*"
  exit 77
}

if [[ $in_netns -eq 0 ]]; then
  command -v Xvfb > /dev/null || skip "Xvfb is not installed (package xvfb; scripts/setup.sh)"
  command -v java > /dev/null || skip "java is not installed (package openjdk-17-jre)"
  command -v python3 > /dev/null || skip "python3 is not installed"
  [[ -n "$probe" && -f "$probe" ]] ||
    skip "the probe jar was not built (CMake found no javac/jar: package default-jdk-headless)"
  [[ -f "$jar" ]] || skip "the cblox types jar was not built: $jar"
  if ! why=$(bash "$spy" --check "$jar" 2>&1); then
    skip "lcm-spy cannot run here: $why"
  fi
  command -v unshare > /dev/null || skip "unshare is not installed (package util-linux)"
  command -v ip > /dev/null || skip "ip is not installed (package iproute2)"
  # As scripts/netns-run.sh, plus a mount namespace with a private /tmp/.X11-unix: an X
  # server in another network namespace does not see the abstract sockets of the machine's
  # X servers, takes display :0 and would replace the machine's /tmp/.X11-unix/X0.
  enter='ip link set lo up && ip route add 224.0.0.0/4 dev lo &&
         mount -t tmpfs -o mode=1777 tmpfs /tmp/.X11-unix'
  [[ -d /tmp/.X11-unix ]] || mkdir -m 1777 /tmp/.X11-unix 2> /dev/null || true
  if ! why=$(unshare -rnm sh -c "$enter" 2>&1); then
    skip "cannot make a network + mount namespace with a multicast route (unshare -rnm): $why"
  fi
  # shellcheck disable=SC2016  # $0 and $@ are for the inner bash
  exec unshare -rnm bash -c "$enter"' && exec bash "$0" --in-netns "$@"' \
    "${BASH_SOURCE[0]}" "$@"
fi

# ---- inside the private network namespace ---------------------------------------------
start=$SECONDS
work="$out_dir/lcm_spy"
rm -rf "$work"
mkdir -p "$work"
png="$out_dir/lcm_spy.png"
rm -f "$png"
url="udpm://239.255.76.67:7667?ttl=0"

pids=()
cleanup() {
  local pid
  for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2> /dev/null || true; done
}
trap cleanup EXIT

fail() {
  echo "FAIL: $*"
  for log in "$work"/*.log; do
    [[ -s "$log" ]] || continue
    echo "---- $(basename "$log") (last 30 lines)"
    tail -n 30 "$log"
  done
  exit 1
}

# wait_for SECONDS PID FILE: until FILE is non-empty; false if PID ends or time runs out.
wait_for() {
  local deadline=$((SECONDS + $1))
  while [[ ! -s "$3" ]]; do
    kill -0 "$2" 2> /dev/null || return 1
    ((SECONDS < deadline)) || return 1
    sleep 0.1
  done
}

# Xvfb picks a free display itself (-displayfd); its socket is in our private /tmp/.X11-unix.
Xvfb -displayfd 3 -screen 0 1600x900x24 -nolisten tcp 3> "$work/display" \
  > "$work/xvfb.log" 2>&1 &
pids+=("$!")
wait_for 15 "${pids[-1]}" "$work/display" || fail "Xvfb did not start"
DISPLAY=":$(head -n 1 "$work/display")"
export DISPLAY
echo "Xvfb on $DISPLAY"

"$publisher" --list > "$work/expected.txt"
channels=$(cut -d' ' -f1 "$work/expected.txt" | paste -sd, -)

# lcm-spy with the probe agent; the script adds its own JVM option in front of ours.
CBLOX_SPY_PROBE_READY="$work/ready" \
CBLOX_SPY_PROBE_CHANNELS="$channels" \
CBLOX_SPY_PROBE_MIN_MSGS=2 \
CBLOX_SPY_PROBE_TIMEOUT_S=40 \
CBLOX_SPY_PROBE_TABLE="$work/table.tsv" \
CBLOX_SPY_PROBE_DECODED="$work/decoded.tsv" \
CBLOX_SPY_PROBE_PNG="$png" \
CBLOX_SPY_PROBE_OPEN=CBLOX_STEREO \
JDK_JAVA_OPTIONS="-javaagent:\"$probe\"" \
  bash "$spy" "$jar" --lcm-url "$url" > "$work/lcm-spy.log" 2>&1 &
spy_pid=$!
pids+=("$spy_pid")
wait_for 30 "$spy_pid" "$work/ready" || fail "lcm-spy did not show its window"
echo "lcm-spy window up after $((SECONDS - start)) s"

# Every channel, 5 times a second for 6 s: lcm-spy subscribes just after its window shows,
# so the first round may come too early; the probe waits for 2 messages a channel, then for
# the bus to go quiet before it reads the counts and opens a viewer (LcmSpyProbe.java, 2b).
"$publisher" "$url" 30 200 > "$work/publisher.log" 2>&1 &
pids+=("$!")
wait_for 45 "$spy_pid" "$work/table.tsv" || fail "the probe wrote no table (lcm-spy ended or hung)"
echo "lcm-spy table read after $((SECONDS - start)) s"
cleanup
pids=()

[[ -s "$png" ]] && echo "screenshot: $png" || echo "(no screenshot; see lcm-spy.log)"
python3 "$here/check_lcm_spy_table.py" "$lcm_dir" "$work/expected.txt" "$work/table.tsv" \
  "$work/decoded.tsv" || fail "lcm-spy did not decode every cblox type"
[[ -s "$png" ]] || fail "no screenshot was written"
echo "PASS in $((SECONDS - start)) s"
