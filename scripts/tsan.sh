#!/usr/bin/env bash
# Builds the multithreaded components' tests with ThreadSanitizer into build-tsan and runs
# them: the integrators (ray casting with per-block spin locks and lock-free hash sets,
# the projective integrator's block partition), the mesher, and the submap collection's
# thread-safety rule (integration, pose updates and fusion on concurrent threads), and the
# mapper's threads (integrator, maintenance, export worker fed from several threads; the mesh
# stream's copy thread), and
# the sparse SLAM's threads (tracking, local mapping with triangulation and local BA, loop
# closing) on the real 7-Scenes RGB-D frames when ../shared/data has them, and
# cblox-capture's dense-stereo thread. The vocabulary
# comes from the Release build (build/, trained there first). Libraries not built with TSan
# are suppressed (scripts/tsan.supp). Exit status is the tests'.
# Usage: scripts/tsan.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ccache_env.sh
BUILD_DIR=build-tsan
RELEASE_DIR=${RELEASE_DIR:-build}
WERROR=OFF
if [[ "${CI:-}" == "true" ]]; then WERROR=ON; fi
# The Release build's vocabulary (the same configure as scripts/build.sh, so nothing is
# built twice).
cmake -S . -B "$RELEASE_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCBLOX_WERROR=$WERROR >/dev/null
cmake --build "$RELEASE_DIR" --target cblox_vocabulary_file -j"$(nproc)"
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS="-fsanitize=thread -fno-omit-frame-pointer" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" -DCBLOX_BUILD_BENCHMARKS=OFF \
  -DCBLOX_BUILD_VOCABULARY=OFF -DCBLOX_VOCABULARY_FILE="$PWD/$RELEASE_DIR/vocabulary/cblox_orb.vocab" \
  >/dev/null
cmake --build "$BUILD_DIR" --target test_integrator test_mesh test_submap test_mapper test_tracking \
  test_stereo_depth_worker test_tracker_node test_planning_map test_planning_service \
  test_planner_example test_mesh_streamer -j"$(nproc)"
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$PWD/scripts/tsan.supp"
"$BUILD_DIR/test/integrator/test_integrator" --gtest_brief=1
"$BUILD_DIR/test/mesh/test_mesh" --gtest_brief=1
"$BUILD_DIR/test/submap/test_submap" --gtest_brief=1
"$BUILD_DIR/test/mapping/test_mapper" --gtest_brief=1
# The mesh stream's copy thread beside integration (the mapper's worker and its runner).
"$BUILD_DIR/test/mapping/test_mesh_streamer" --gtest_brief=1
# The planning map's fields refreshed beside queries, its query thread, and a Mapper with
# planning on (the worker's and the cblox-esdf thread's refreshes beside integration).
"$BUILD_DIR/test/mapping/test_planning_map" --gtest_brief=1
"$BUILD_DIR/test/mapping/test_planning_service" --gtest_brief=1
"$BUILD_DIR/test/mapping/test_planner_example" --gtest_brief=1
"$BUILD_DIR/test/tracking/test_tracking" --gtest_brief=1 \
  --gtest_filter='RgbdTrackingTest.*:SparseMapTest.*:KeyframeTriangulationTest.*'
"$BUILD_DIR/test/daemon/test_stereo_depth_worker" --gtest_brief=1
# The tracker's checkpoint writer and id lease beside its tracking and SLAM threads.
"$BUILD_DIR/test/daemon/test_tracker_node" --gtest_brief=1 \
  --gtest_filter='TrackerResumeTest.*:IdLeaseKeeperTest.*'
echo "tsan: no data race reported"
