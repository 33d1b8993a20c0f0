#!/usr/bin/env bash
# The stereo-only path end to end over LCM: cblox-capture renders the room with its depth
# camera switched off and publishes SGBM depth of the rectified pair (the example config),
# cblox-mapper integrates it at the exact poses, and the mesh is evaluated against the exact
# scene. 150 frames of the loop; measured 14.3 mm median, 85.7 % precision, 23.2 %
# completeness (the depth camera on the same frames: sub-millimetre). Bounds leave room for
# frames superseded on a loaded machine.
# Usage: run_stereo_pipeline_test.sh BUILD_DIR
set -euo pipefail
build=$1
cd "$(dirname "$0")/../.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
BUILD_DIR=$build scripts/run_pipeline.sh --scene room --trajectory loop --frames 150 \
  --poses ground_truth --capture-config config/examples/sim_stereo_depth.yaml \
  --out "$tmp" --name stereo > "$tmp/run.log" 2>&1 || { cat "$tmp/run.log"; exit 1; }
grep -E "stereo depth|accuracy|completeness" "$tmp/run.log"
grep -q "stereo depth 1[0-9][0-9] frames" "$tmp/run.log" || {
  echo "FAIL: fewer than 100 depth frames computed"; exit 1; }
/usr/bin/env python3 - "$tmp/stereo_eval.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))["mesh"]
median = m["accuracy"]["median_m"]
precision = m["completeness"]["precision"]
completeness = m["completeness"]["completeness"]
ok = median < 0.025 and precision > 0.78 and completeness > 0.18
print(f"median {1000 * median:.1f} mm (< 25), precision {100 * precision:.1f} % (> 78), "
      f"completeness {100 * completeness:.1f} % (> 18): {'ok' if ok else 'FAIL'}")
sys.exit(0 if ok else 1)
PY
