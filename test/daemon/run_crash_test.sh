#!/usr/bin/env bash
# The kill -9 crash test, short (scripts/crash_test.sh: capture + tracker + mapper in a private
# network namespace; the mapper killed during integration, fusion and checkpoint writes, or the
# tracker while tracking and during checkpoint writes, each kill followed by a verified resume
# with nothing acknowledged lost). The full runs are `scripts/crash_test.sh --kills 200
# [--victims tracker]`.
# Usage: run_crash_test.sh BUILD_DIR WORK_DIR [KILLS] [VICTIM]
set -euo pipefail
build=$1
work=$2
kills=${3:-9}
victim=${4:-mapper}
repo=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$work"
mkdir -p "$work"
# A pause of 100 ms (40 by default) before each checkpoint file: on a loaded CI machine the
# harness itself is slow to see a checkpoint start, and the test needs a kill inside one.
BUILD_DIR=$build exec "$repo/scripts/crash_test.sh" --victims "$victim" --kills "$kills" \
  --pause-ms 100 --work "$work/run" --report "$work/crash_$victim.md"
