#!/usr/bin/env bash
# A unit started without its config (the file named by --config is missing): every daemon
# exits 2 (usage or configuration error, which the systemd units do not restart) with one
# line naming itself and the file.
# Usage: run_missing_config_test.sh BIN_DIR
set -uo pipefail
bin=$1
missing=/nonexistent/cblox/missing.yaml
for daemon in cblox-capture cblox-tracker cblox-mapper; do
  output=$("$bin/$daemon" --config "$missing" 2>&1)
  status=$?
  [[ $status -eq 2 ]] || { echo "FAIL: $daemon exited with $status, not 2: $output"; exit 1; }
  [[ "$output" == "$daemon: configuration error: $missing: cannot open config file" ]] \
    || { echo "FAIL: $daemon said: $output"; exit 1; }
  echo "$daemon: $output (exit 2)"
done
echo PASS
