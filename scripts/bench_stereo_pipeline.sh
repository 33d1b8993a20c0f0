#!/usr/bin/env bash
# The whole pipeline on stereo only (the depth camera switched off: SGBM or block-matching
# depth from the rectified pair at half size -> mapper) against the same run with the depth
# camera, on the simulated room and hall (one loop at 20 Hz), with the tracker's poses and with
# exact poses; each mesh evaluated against the exact scene (cblox-eval). Prints one table; the
# runs are in out/stereo_pipeline/.
# Usage: scripts/bench_stereo_pipeline.sh [--scenes "room hall"] [--trajectory loop] [--out DIR]
# Needs a build (scripts/build.sh); BUILD_DIR selects it. Each run is real time (20 Hz).
set -euo pipefail
cd "$(dirname "$0")/.."
scenes="room hall" out=out/stereo_pipeline trajectory=loop
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scenes) scenes=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --trajectory) trajectory=$2; shift 2 ;;
    *) echo "bench_stereo_pipeline: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
# sgbm: the example config as it is; bm: the same with block matching (9x9 blocks).
bm_config=$(mktemp --suffix .yaml)
trap 'rm -f "$bm_config"' EXIT
sed -e 's/^  matcher: sgbm/  matcher: bm/' -e 's/^  block_size: 5/  block_size: 9/' \
  config/examples/sim_stereo_depth.yaml > "$bm_config"
rows=()
for scene in $scenes; do
  for depth in camera sgbm bm; do
    for poses in tracker ground_truth; do
      name="${scene}_${depth}_${poses}"
      case $depth in
        camera) config=config/capture.yaml ;;
        sgbm) config=config/examples/sim_stereo_depth.yaml ;;
        bm) config=$bm_config ;;
      esac
      echo "bench_stereo_pipeline: $name"
      scripts/run_pipeline.sh --scene "$scene" --trajectory "$trajectory" --poses "$poses" \
        --capture-config "$config" \
        --out "$out" --name "$name" > "$out/$name.log" 2>&1 || { echo "  failed, see $out/$name.log"; continue; }
      rows+=("$(/usr/bin/env python3 - "$out/${name}_eval.json" "$name" "$out/$name.log" <<'PY'
import json, re, sys
e = json.load(open(sys.argv[1]))
log = open(sys.argv[3]).read()
m = re.search(r"stereo depth (\d+) frames, ([\d.]+) ms mean", log)
a, c = e["mesh"]["accuracy"], e["mesh"]["completeness"]
print(f"{sys.argv[2]:28s} {1000*a['median_m']:7.1f} {1000*a['p90_m']:7.1f} {1000*a['rmse_m']:7.1f} "
      f"{100*c['completeness']:6.1f}% {100*c['precision']:6.1f}% "
      f"{(m.group(2) + ' ms') if m else '-':>9s}")
PY
)")
    done
  done
done
echo
printf "%-28s %7s %7s %7s %7s %7s %9s\n" "run" "median" "p90" "RMSE" "compl." "prec." "matcher"
printf "%-28s %7s %7s %7s %7s %7s %9s\n" "" "mm" "mm" "mm" "" "" "mean"
for row in "${rows[@]}"; do echo "$row"; done
