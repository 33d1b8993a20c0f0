#!/usr/bin/env bash
# The CI version of scripts/overload_test.sh (README "Memory cap and overload"): cblox-capture
# renders the room live at 20 Hz, 4x the overload mapper's budget-bound ~5 frames/s (1 cm
# voxels, fast integrator, 0.2 s budget), into cblox-mapper (ground-truth poses) for ~35 s
# with a 64 MiB memory cap. Fails unless both stop cleanly, the mapper's peak RSS stays
# under the bound (1.25 x cap + 192 MiB), drops are counted, integrated frames are fresh
# (age p99 <= 1 s: newest frame wins) and the cap engaged (frames integrated at the cap).
# Usage: run_overload_test.sh BIN_DIR WORK_DIR
set -euo pipefail
bin=$1
work=$2
repo=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$work"
mkdir -p "$work"
CBLOX_BIN="$bin" "$repo/scripts/overload_test.sh" --minutes 0.6 --factors 4 --mapper-rate 5 \
  --source live --poses ground_truth --cap-mb 64 --check --expect-cap --out "$work"
