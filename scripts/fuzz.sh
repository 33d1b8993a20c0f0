#!/usr/bin/env bash
# Builds the libFuzzer targets of test/fuzz (clang-14, ASan + UBSan, ccache) in build-fuzz and
# runs each one in turn on its seed corpus (test/fuzz/corpus/<target>) and its regressions
# (test/fuzz/regressions/<target>); new inputs go to build-fuzz/corpus/<target>, crashes to
# build-fuzz/artifacts/<target>/, each run's output to build-fuzz/logs/<target>.log. Prints a
# table: target, executions, exec/s, seconds, edges covered at the end, new coverage (inputs
# added), corpus size, crashes.
# Exit status 1 when a target crashed (or leaked, hit UB, timed out), else 0.
#
# Usage: scripts/fuzz.sh [--ci | --runs N | --seconds S] [--build-only | --no-build] [target ...]
#   --ci          bounded: about 90 s in total over all targets (CI; the default)
#   --runs N      N executions per target (e.g. --runs 1000000)
#   --seconds S   at most S seconds per target (with --runs: whichever comes first)
#   --no-build    run what build-fuzz holds (e.g. while another build of it is running)
#   target ...    only these (names as in test/fuzz/CMakeLists.txt, e.g. fuzz_ply)
# Environment: CCACHE_DISABLE=1 for a cold build; FUZZ_FLAGS for more libFuzzer flags.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ccache_env.sh
BUILD_DIR=build-fuzz
CI_TOTAL_SECONDS=90
mode=ci
runs=0
seconds=0
build_only=false
build=true
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --ci) mode=ci ;;
    --runs) mode=long; runs="$2"; shift ;;
    --seconds) mode=long; seconds="$2"; shift ;;
    --build-only) build_only=true ;;
    --no-build) build=false ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1") ;;
  esac
  shift
done
# The targets: every cblox_fuzz_target(...) line of test/fuzz/CMakeLists.txt.
mapfile -t all_targets < <(sed -n 's/^cblox_fuzz_target(\([a-z0-9_]*\).*/\1/p' test/fuzz/CMakeLists.txt)
if [[ ${#targets[@]} -eq 0 ]]; then targets=("${all_targets[@]}"); fi

if $build && ! command -v clang++-14 >/dev/null; then
  echo "fuzz.sh: clang++-14 not found (scripts/setup.sh installs clang-14 and libclang-rt-14-dev)" >&2
  exit 2
fi
if $build; then
  # Sanitizers and coverage are added per library by test/fuzz/CMakeLists.txt (the code hostile
  # bytes reach); -O1 with line tables keeps stacks readable and the build short.
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    -DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache \
    -DCMAKE_C_FLAGS="-fno-omit-frame-pointer" -DCMAKE_CXX_FLAGS="-fno-omit-frame-pointer" \
    -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DCBLOX_FUZZ=ON -DCBLOX_BUILD_TESTS=OFF -DCBLOX_BUILD_BENCHMARKS=OFF \
    -DCBLOX_BUILD_VOCABULARY=OFF -DCBLOX_WERROR=OFF >/dev/null
  build_start=$(date +%s)
  cmake --build "$BUILD_DIR" --target "${targets[@]}" -j"$(nproc)"
  echo "fuzz: build took $(( $(date +%s) - build_start )) s"
fi
if $build_only; then exit 0; fi

limit=()
if [[ $mode == ci ]]; then
  per_target=$(( CI_TOTAL_SECONDS / ${#targets[@]} ))
  if (( per_target < 3 )); then per_target=3; fi
  limit=(-max_total_time="$per_target")
fi
if (( runs > 0 )); then limit+=(-runs="$runs"); fi
if (( seconds > 0 )); then limit+=(-max_total_time="$seconds"); fi

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
final_stat() { sed -n "s/^stat::$1: *//p" "$2" | tail -1; }
rows=()
failed=0
for t in "${targets[@]}"; do
  corpus="$BUILD_DIR/corpus/$t"
  artifacts="$BUILD_DIR/artifacts/$t"
  log="$BUILD_DIR/logs/$t.log"
  mkdir -p "$corpus" "$artifacts" "$(dirname "$log")"
  if [[ ! -d "test/fuzz/corpus/$t" ]]; then
    echo "fuzz.sh: $t has no seed corpus test/fuzz/corpus/$t (is it committed?)" >&2
    failed=1
    continue
  fi
  inputs=("$corpus" "test/fuzz/corpus/$t")
  if [[ -d "test/fuzz/regressions/$t" ]]; then inputs+=("test/fuzz/regressions/$t"); fi
  before=$(find "$corpus" -type f | wc -l)
  start=$(date +%s.%N)
  status=0
  # shellcheck disable=SC2086
  "$BUILD_DIR/test/fuzz/$t" "${limit[@]}" -timeout=25 -rss_limit_mb=2560 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" ${FUZZ_FLAGS:-} \
    "${inputs[@]}" >"$log" 2>&1 || status=$?
  elapsed=$(echo "$(date +%s.%N) - $start" | bc)
  after=$(find "$corpus" -type f | wc -l)
  crashes=$(( status == 0 ? 0 : 1 ))
  if (( crashes )); then failed=1; fi
  edges=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2 || true)
  rows+=("$(printf '%-26s %12s %8s %8.1f %7s %6s %7s %8s' "$t" "$(final_stat number_of_executed_units "$log")" \
    "$(final_stat average_exec_per_sec "$log")" "$elapsed" "${edges:-?}" "$(( after - before ))" \
    "$(( after + $(find "test/fuzz/corpus/$t" -type f | wc -l) ))" "$crashes")")
  echo "${rows[-1]}"
  if (( crashes )); then
    echo "fuzz: $t failed (exit $status), see $log and $artifacts/; its last lines:" >&2
    tail -n 30 "$log" >&2
  fi
done
echo
printf '%-26s %12s %8s %8s %7s %6s %7s %8s\n' target executions exec/s seconds edges new corpus crashes
printf '%s\n' "${rows[@]}"
exit $failed
