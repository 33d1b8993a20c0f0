#pragma once

// Shared set-up for the persistence tests: a collection of submaps with real integrated content
// (the analytic sphere scene of test/submap) plus hand-written awkward voxels, and a bit-exact
// comparison of two collections. Test-only; not thread-safe.

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "core/persistence/map_manifest.h"
#include "core/persistence/submap_file.h"
#include "core/submap/submap_collection.h"
#include "test/submap/submap_test_scene.h"

namespace cblox::test {

inline SubmapCollectionConfig mapTestConfig() {
  SubmapCollectionConfig config;
  config.layer = LayerConfig{kVoxelSize, 8};
  return config;
}

inline Transformationd mapTestPose(double angle, const Eigen::Vector3d& axis,
                                   const Eigen::Vector3d& t) {
  return Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized())), t);
}

/// Voxels no integrator writes but the format must keep bit-exact: -0, a denormal, NaN with a
/// payload, infinities, extreme colours; in blocks with negative and far indices.
inline void writeAwkwardVoxels(TsdfLayer* layer) {
  Block* a = layer->allocateBlock(BlockIndex(-1, -7, 3));
  a->voxel(0) = TsdfVoxel{-0.0f, 1.0f, Color{255, 0, 255}};
  a->voxel(1) = TsdfVoxel{std::numeric_limits<float>::denorm_min(), 3.5f, Color{1, 2, 3}};
  uint32_t nan_bits = 0x7fc01234u;
  float nan;
  std::memcpy(&nan, &nan_bits, sizeof(nan));
  a->voxel(511) = TsdfVoxel{nan, std::numeric_limits<float>::infinity(), Color{9, 8, 7}};
  Block* b = layer->allocateBlock(BlockIndex(kGridIndexMin, kGridIndexMax, 0));
  for (int i = 0; i < b->numVoxels(); ++i) {
    b->voxel(i) = TsdfVoxel{
        0.001f * static_cast<float>(i - 256), static_cast<float>(i % 17),
        Color{static_cast<uint8_t>(i), static_cast<uint8_t>(i * 7), static_cast<uint8_t>(255 - i)}};
  }
}

/// Submaps 0 (finished, three keyframes), 1 (finished, awkward voxels, moved by a pose
/// update), 2 (removed), 3 (finished, empty) and 4 (active, integrated); next id 5.
inline std::unique_ptr<SubmapCollection> buildTestCollection() {
  static const std::vector<SyntheticFrame> frames = renderOrbit(12);
  auto collection = std::make_unique<SubmapCollection>(mapTestConfig());
  auto s0 = collection->createSubmap(mapTestPose(0.1, {0, 0, 1}, {0.1, 0.2, 0.3}), 10, 1000);
  integrateFrames(s0.get(), frames, 0, 4);
  s0->addKeyframe(11);
  s0->addKeyframe(13);
  auto s1 = collection->createSubmap(mapTestPose(-0.7, {1, 2, 3}, {1, -2, 0.5}), 20, 2000);
  integrateFrames(s1.get(), frames, 4, 8);
  {
    Submap::WriteLock lock = s1->lockForIntegration();
    writeAwkwardVoxels(&lock.layer());
  }
  collection->createSubmap(Transformationd(), 30, 3000);
  collection->createSubmap(mapTestPose(0.3, {0, 1, 0}, {0, 0, 1}), 40, 4000);
  auto s4 = collection->createSubmap(mapTestPose(2.0, {1, 0, 0}, {-3, 4, 5}), 50, 5000);
  integrateFrames(s4.get(), frames, 8, 12);
  s4->addKeyframe(51);
  collection->removeSubmap(2);
  collection->updateKeyframePoses({{20, mapTestPose(-0.69, {1, 2, 3.1}, {1.01, -2, 0.5})}});
  return collection;
}

/// Expects equal collections: ids, next id, active submap, anchors, creation times, keyframes,
/// finished flags, poses (translation exact, rotation within 1e-15: the quaternion is
/// renormalised on load) and every voxel of every block bit-identical (memcmp).
inline void expectSameCollection(const SubmapCollection& a, const SubmapCollection& b) {
  ASSERT_EQ(a.submapIds(), b.submapIds());
  EXPECT_EQ(a.nextSubmapId(), b.nextSubmapId());
  const auto active_a = a.activeSubmap(), active_b = b.activeSubmap();
  ASSERT_EQ(active_a == nullptr, active_b == nullptr);
  if (active_a) {
    EXPECT_EQ(active_a->id(), active_b->id());
  }
  EXPECT_EQ(a.config().layer.voxel_size, b.config().layer.voxel_size);
  EXPECT_EQ(a.config().layer.voxels_per_side, b.config().layer.voxels_per_side);
  for (const SubmapId id : a.submapIds()) {
    SCOPED_TRACE("submap " + std::to_string(id));
    const auto sa = a.getSubmap(id), sb = b.getSubmap(id);
    EXPECT_EQ(sa->anchorKeyframe(), sb->anchorKeyframe());
    EXPECT_EQ(sa->creationTimeNs(), sb->creationTimeNs());
    EXPECT_EQ(sa->keyframeIds(), sb->keyframeIds());
    EXPECT_EQ(sa->isFinished(), sb->isFinished());
    EXPECT_EQ(sa->numBlocks(), sb->numBlocks());
    EXPECT_TRUE(sa->T_G_M().translation() == sb->T_G_M().translation());
    EXPECT_LE(
        (sa->T_G_M().rotation().coeffs() - sb->T_G_M().rotation().coeffs()).cwiseAbs().maxCoeff(),
        1e-15);
    EXPECT_TRUE(sameVoxels(layerVoxels(sa->layer()), layerVoxels(sb->layer())));
  }
}

/// A consistent manifest (no submap files behind it): generation 3, submaps 2 (finished,
/// extreme pose) and 8 (active), three counters, no maintenance section content.
inline MapManifest smallManifest() {
  MapManifest m;
  m.generation = 3;
  m.config = mapTestConfig();
  m.next_submap_id = 9;
  m.active_submap_id = 8;
  SubmapRecord a;
  a.id = 2;
  a.anchor_keyframe = 20;
  a.creation_time_ns = -5;
  a.T_G_M = mapTestPose(0.4, {1, 1, 0}, {1e-300, -2.5, 1e300});
  a.finished = true;
  a.keyframe_ids = {3, 20, 21};
  a.file = {submapFileName(2, 1), 1234, 0xdeadbeefcafef00dull, 17};
  SubmapRecord b;
  b.id = 8;
  b.anchor_keyframe = -1;
  b.keyframe_ids = {-1};
  b.file = {submapFileName(8, 3), 40, 1, 0};
  m.submaps = {a, b};
  m.counters = {{"frames_integrated", 123456789012345}, {"fusions", -1}, {"x", 0}};
  return m;
}

}  // namespace cblox::test
