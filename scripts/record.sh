#!/usr/bin/env bash
# Records cblox's sensor channels with LCM's own lcm-logger, so that a run can be played
# again with lcm-logplayer (into cblox-tracker + cblox-mapper, live) or cblox-replay
# (offline, deterministic, as fast as the CPU allows).
#
# Usage: scripts/record.sh [--lcm-url URL] [--all | --channels REGEX] [--split-mb N]
#                          [--force] FILE.lcmlog
#   default channels: CBLOX_STEREO|CBLOX_DEPTH|CBLOX_GT_POSE (what cblox-capture publishes;
#                     everything the tracker and the mapper are computed from)
#   --all             every channel (the processes' outputs, heartbeats, commands too):
#                     for looking at a run, not needed to replay it
#   --split-mb N      a new file every N MB (FILE.00, FILE.01, ...; lcm-logger -i)
#   --lcm-url URL     default: $LCM_DEFAULT_URL, else LCM's default (udpm, ttl=0). Image
#                     traffic needs a receive buffer: add recv_buf_size=4194304 to a udpm
#                     URL, and net.core.rmem_max >= that (config/sysctl/60-cblox-lcm.conf).
# Stops on Ctrl-C / SIGTERM (the log stays valid: lcm-logger flushes every 100 ms; a log
# cut short by a kill is read up to its last whole event). Exit status: lcm-logger's, 2 usage.
set -euo pipefail

usage() { sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; }

channels='CBLOX_STEREO|CBLOX_DEPTH|CBLOX_GT_POSE'
url="${LCM_DEFAULT_URL:-}"
split="" force=() file=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --lcm-url) url=$2; shift 2 ;;
    --all) channels='.*'; shift ;;
    --channels) channels=$2; shift 2 ;;
    --split-mb) split=$2; shift 2 ;;
    --force) force=(--force); shift ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "record.sh: unknown option '$1'" >&2; usage >&2; exit 2 ;;
    *) [[ -z "$file" ]] || { echo "record.sh: one FILE only" >&2; exit 2; }; file=$1; shift ;;
  esac
done
if [[ -z "$file" ]]; then
  echo "record.sh: missing FILE.lcmlog" >&2
  usage >&2
  exit 2
fi
if ! command -v lcm-logger > /dev/null; then
  echo "record.sh: lcm-logger not found: apt-get install liblcm-bin" >&2
  exit 2
fi
args=(--channel="$channels" "${force[@]}")
[[ -n "$url" ]] && args+=(--lcm-url="$url")
[[ -n "$split" ]] && args+=(--increment --split-mb="$split")
mkdir -p "$(dirname "$file")"
echo "record.sh: recording /$channels/ to $file${url:+ from $url} (Ctrl-C stops)" >&2
exec lcm-logger "${args[@]}" "$file"
