#!/usr/bin/env bash
# Builds the multithreaded components' tests with ThreadSanitizer into build-tsan and runs
# them: the integrators (ray casting with per-block spin locks and lock-free hash sets,
# the projective integrator's block partition), the mesher, and the submap collection's
# thread-safety rule (integration, pose updates and fusion on concurrent threads), and the
# mapper's threads (integrator, maintenance, export worker fed from several threads).
# Exit status is the tests'.
# Usage: scripts/tsan.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=build-tsan
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS="-fsanitize=thread -fno-omit-frame-pointer" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" -DCBLOX_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$BUILD_DIR" --target test_integrator test_mesh test_submap test_mapper -j"$(nproc)"
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1"
"$BUILD_DIR/test/integrator/test_integrator" --gtest_brief=1
"$BUILD_DIR/test/mesh/test_mesh" --gtest_brief=1
"$BUILD_DIR/test/submap/test_submap" --gtest_brief=1
"$BUILD_DIR/test/daemon/test_mapper" --gtest_brief=1
echo "tsan: no data race reported"
