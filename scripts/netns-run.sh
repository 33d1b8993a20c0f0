#!/usr/bin/env bash
# Runs a command in a private network namespace (unprivileged: a user namespace maps us to
# root inside) with loopback up and a multicast route on it, so LCM traffic of this run can
# neither reach nor hear any other process on the machine.
# Usage: scripts/netns-run.sh COMMAND [ARGS...]
set -euo pipefail
if [[ $# -eq 0 ]]; then
  echo "usage: $0 COMMAND [ARGS...]" >&2
  exit 2
fi
exec unshare -rn bash -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$@"' \
  netns-run "$@"
