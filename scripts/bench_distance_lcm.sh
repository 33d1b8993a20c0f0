#!/usr/bin/env bash
# A planner asking distances while the map is being built: cblox-capture renders the
# simulated room at 20 Hz into cblox-mapper (ground-truth poses, shipped config with
# planning on: --planning), and cblox-bench-distance-lcm sends distance requests of 4096
# random points of the room at 10 Hz meanwhile, measuring each round trip (publish to reply,
# over UDP multicast on loopback), in a private network namespace (scripts/netns-run.sh).
# Prints the round trips and the mapper's own integration figures (its "stopped:" line), so
# that a request load that slowed integration would show.
#
# Usage: scripts/bench_distance_lcm.sh [--frames N (400)] [--requests N (300)]
#                                      [--points N (4096)] [--rate HZ (10)] [--out DIR (out)]
#                                      [--mapper-config FILE (config/mapper.yaml)]
#                                      [--no-planning]  (the mapper without distance fields:
#                                       every request is answered NO_PLANNING_MAP at once, the
#                                       bus's own round trip, and integration without the
#                                       fields, for comparison)
# Needs a build (BUILD_DIR, default build). Exit status: 0 done, 1 a process failed, 2 usage.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
frames=400 requests=300 points=4096 rate=10 out=out mapper_config=config/mapper.yaml
planning=--planning
while [[ $# -gt 0 ]]; do
  case "$1" in
    --frames) frames=$2; shift 2 ;;
    --requests) requests=$2; shift 2 ;;
    --points) points=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --mapper-config) mapper_config=$2; shift 2 ;;
    --no-planning) planning=""; shift ;;
    *) echo "bench_distance_lcm: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
if [[ "${CBLOX_IN_NETNS:-}" != "1" ]]; then
  CBLOX_IN_NETNS=1 exec scripts/netns-run.sh "$0" --frames "$frames" --requests "$requests" \
    --points "$points" --rate "$rate" --out "$out" --mapper-config "$mapper_config" \
    $([[ -z $planning ]] && echo --no-planning)
fi
bin=$(cd "$BUILD_DIR" && pwd)
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
"$bin/daemon/cblox-mapper" --config "$mapper_config" --pose-source ground_truth $planning \
  --output-dir "$out" --lcm-url "$url" > "$out/bench_distance_mapper.log" 2>&1 &
mapper=$!
trap 'kill -TERM $mapper 2>/dev/null || true' EXIT
sleep 1
"$bin/daemon/cblox-capture" --source sim:room --trajectory orbit --frames "$frames" --rate 20 \
  --lcm-url "$url" --quiet &
capture=$!
sleep 3  # a first map to ask about
echo "bench_distance_lcm: $requests requests of $points points at $rate Hz while the room is mapped"
"$bin/test/bench/cblox-bench-distance-lcm" --lcm-url "$url" --requests "$requests" \
  --points "$points" --rate "$rate" --box=0,0,0,5,6.5,2.7 \
  --json "$out/bench_distance_lcm.json"
wait $capture
sleep 2
kill -TERM $mapper
wait $mapper || { echo "bench_distance_lcm: cblox-mapper exited with $?" >&2; exit 1; }
trap - EXIT
grep -E "^mapper: stopped" "$out/bench_distance_mapper.log" || true
