#!/usr/bin/env bash
# cblox-calib on real pairs: calibrates the 13 chessboard stereo pairs Debian's opencv-doc
# ships, checks the rectified row error of that calibration (< 0.5 px, against > 5 px in the raw
# images), refuses a calibration whose right camera is turned by half a degree about x (the
# rows then miss by pixels: exit 1), and checks EuRoC's own calibration on the EuRoC pairs of
# ../shared/data. Usage errors exit 2. Exit 77 (skipped) without opencv-doc.
# Usage: run_calib_test.sh BIN_DIR SHARED_DATA_DIR
set -euo pipefail
bin=$1 data=$2
doc=/usr/share/doc/opencv-doc/examples/data
if [[ ! -f $doc/stereo_calib.xml || ! -f $doc/left01.jpg ]]; then
  echo "SKIP: opencv-doc's chessboard pairs are not installed (apt-get install opencv-doc)"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$bin/cblox-calib" calibrate --list "$doc/stereo_calib.xml" --pattern 9x6 --square 0.025 \
  --out "$tmp/rig.yml" > "$tmp/calibrate.log"
grep -q "calibrated on 13 pairs" "$tmp/calibrate.log" || fail "not calibrated on 13 pairs: $(cat "$tmp/calibrate.log")"
"$bin/cblox-calib" check --calibration "$tmp/rig.yml" --list "$doc/stereo_calib.xml" > "$tmp/check.log"
cat "$tmp/check.log"
rectified=$(awk '/^rectified:/ {print $7}' "$tmp/check.log")
raw=$(awk '/^raw images:/ {print $8}' "$tmp/check.log")
awk -v r="$rectified" 'BEGIN {exit !(r < 0.5)}' || fail "rectified row error $rectified px"
awk -v r="$raw" 'BEGIN {exit !(r > 5.0)}' || fail "raw row error $raw px should be large"

# Turn the right camera by 0.5 degrees about x: its rows move by ~ fy * 0.0087 ~ 5 px.
sed -n '1,/^R:/p' "$tmp/rig.yml" | head -n -1 > "$tmp/bad.yml"
cat >> "$tmp/bad.yml" <<'YML'
R: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 1., 0., 0., 0., 0.99996192, -0.00872654, 0., 0.00872654, 0.99996192 ]
YML
sed -n '/^T:/,$p' "$tmp/rig.yml" >> "$tmp/bad.yml"
set +e
"$bin/cblox-calib" check --calibration "$tmp/bad.yml" --list "$doc/stereo_calib.xml" > "$tmp/bad.log" 2>&1
status=$?
set -e
[[ $status -eq 1 ]] || fail "a wrong calibration gave exit $status: $(tail -3 "$tmp/bad.log")"
grep -q "does not fit these cameras" "$tmp/bad.log" || fail "no reason given: $(tail -3 "$tmp/bad.log")"

# Usage and input errors: exit 2 with a message.
set +e
"$bin/cblox-calib" check --list "$doc/stereo_calib.xml" > /dev/null 2> "$tmp/usage.log"
[[ $? -eq 2 ]] || fail "check without a calibration did not exit 2"
"$bin/cblox-calib" check --calibration "$tmp/absent.yml" --list "$doc/stereo_calib.xml" \
  > /dev/null 2> "$tmp/absent.log"
[[ $? -eq 2 ]] || fail "a missing calibration file did not exit 2"
set -e
grep -q "absent.yml: cannot open" "$tmp/absent.log" || fail "$(cat "$tmp/absent.log")"

if [[ -d $data/euroc-v101-micro ]]; then
  "$bin/cblox-calib" check --euroc "$data/euroc-v101-micro" --frames 5 > "$tmp/euroc.log"
  cat "$tmp/euroc.log"
  euroc=$(awk '/^rectified:/ {print $7}' "$tmp/euroc.log")
  awk -v r="$euroc" 'BEGIN {exit !(r < 0.5)}' || fail "EuRoC rectified row error $euroc px"
else
  echo "note: $data/euroc-v101-micro absent, EuRoC part skipped"
fi
echo "calib test: ok"
