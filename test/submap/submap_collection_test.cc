#include "core/submap/submap_collection.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <gtest/gtest.h>

#include "core/mesh/mesh.h"
#include "test/submap/submap_test_scene.h"

namespace cblox {
namespace {

Transformationd pose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  return Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized())), t);
}

SubmapCollectionConfig collectionConfig() {
  SubmapCollectionConfig config;
  config.layer = LayerConfig{test::kVoxelSize, 8};
  return config;
}

TEST(SubmapCollectionConfig, ValidateNamesTheField) {
  SubmapCollectionConfig config = collectionConfig();
  EXPECT_EQ(config.validate(), "");
  config.layer.voxels_per_side = 6;
  EXPECT_NE(config.validate().find("layer.voxels_per_side"), std::string::npos);
  EXPECT_THROW(SubmapCollection{config}, std::invalid_argument);
}

TEST(Submap, MetadataAndLifeCycle) {
  const Transformationd T_G_M = pose(0.3, {0, 0, 1}, {1, 2, 3});
  Submap submap(7, LayerConfig{}, T_G_M, 42, 123456789);
  EXPECT_EQ(submap.id(), 7);
  EXPECT_EQ(submap.anchorKeyframe(), 42);
  EXPECT_EQ(submap.creationTimeNs(), 123456789);
  EXPECT_TRUE(submap.T_G_M().isApprox(T_G_M, 0.0));
  EXPECT_TRUE(submap.hasKeyframe(42));
  EXPECT_EQ(submap.numKeyframes(), 1u);
  EXPECT_TRUE(submap.addKeyframe(50));
  EXPECT_FALSE(submap.addKeyframe(50));
  EXPECT_TRUE(submap.addKeyframe(43));
  EXPECT_EQ(submap.keyframeIds(), (std::vector<KeyframeId>{42, 43, 50}));
  EXPECT_FALSE(submap.setT_G_M(
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::nan(""), 0, 0))));
  EXPECT_TRUE(submap.T_G_M().isApprox(T_G_M, 0.0));

  // T_M_C = T_G_M^-1 T_G_C.
  const Transformationd T_G_C = pose(-0.2, {1, 1, 0}, {0.5, -1, 2});
  const Eigen::Vector3d p_C(0.1, 0.2, 1.5);
  EXPECT_LT(((T_G_M * (submap.T_M_C(T_G_C).cast<double>() * p_C)) - T_G_C * p_C).norm(), 1e-6);

  EXPECT_TRUE(submap.isActive());
  EXPECT_EQ(submap.numBlocks(), 0u);
  {
    Submap::WriteLock lock = submap.lockForIntegration();
    ASSERT_TRUE(lock);
    lock.layer().allocateBlock(BlockIndex(1, 2, 3));
    lock.layer().allocateBlock(BlockIndex(-1, 0, 0));
  }
  EXPECT_EQ(submap.numBlocks(), 2u);  // refreshed when the write lock was released
  EXPECT_EQ(submap.memoryBytes(), submap.layer().memoryBytes());
  submap.finish();
  submap.finish();  // idempotent
  EXPECT_TRUE(submap.isFinished());
  EXPECT_FALSE(submap.lockForIntegration());
  EXPECT_THROW(
      Submap(0, LayerConfig{},
             Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Constant(INFINITY)),
             1, 0),
      std::invalid_argument);
}

// revision() changes whenever the layer may have changed: an integration write lock
// released, mutableLayer() handed out, a restored layer; not for metadata or empty locks.
TEST(Submap, RevisionBumpsWhenTheLayerMayHaveChanged) {
  Submap submap(3, LayerConfig{}, Transformationd(), 1, 0);
  EXPECT_EQ(submap.revision(), 0u);
  EXPECT_TRUE(submap.addKeyframe(2));
  EXPECT_TRUE(submap.setT_G_M(pose(0.1, {0, 0, 1}, {1, 0, 0})));
  EXPECT_EQ(submap.revision(), 0u);  // metadata only
  {
    Submap::WriteLock lock = submap.lockForIntegration();
    ASSERT_TRUE(lock);
    lock.layer().allocateBlock(BlockIndex(0, 0, 0));
    EXPECT_EQ(submap.revision(), 0u);  // not before the frame is done
  }
  EXPECT_EQ(submap.revision(), 1u);
  {
    Submap::WriteLock lock = submap.lockForIntegration();
    lock.unlock();
    lock.unlock();  // released once: one bump
  }
  EXPECT_EQ(submap.revision(), 2u);
  submap.finish();
  EXPECT_FALSE(submap.lockForIntegration());  // empty lock: no bump
  EXPECT_EQ(submap.revision(), 2u);
  (void)submap.layer();
  EXPECT_EQ(submap.revision(), 2u);  // reading does not count
  submap.mutableLayer()->allocateBlock(BlockIndex(1, 0, 0));
  EXPECT_EQ(submap.revision(), 3u);

  TsdfLayer layer(LayerConfig{});
  layer.allocateBlock(BlockIndex(0, 0, 0));
  const Submap restored(4, std::move(layer), Transformationd(), 1, 0);
  EXPECT_EQ(restored.revision(), 1u);
}

TEST(SubmapCollection, CreateActivateRemoveIterate) {
  SubmapCollection collection(collectionConfig());
  EXPECT_TRUE(collection.empty());
  EXPECT_EQ(collection.activeSubmap(), nullptr);
  const auto s0 = collection.createSubmap(pose(0.1, {0, 0, 1}, {0, 0, 0}), 10, 1000);
  const auto s1 = collection.createSubmap(pose(0.2, {0, 0, 1}, {1, 0, 0}), 20, 2000);
  EXPECT_EQ(s0->id(), 0);
  EXPECT_EQ(s1->id(), 1);
  EXPECT_TRUE(s0->isFinished());  // the previous active submap is finished
  EXPECT_TRUE(s1->isActive());
  EXPECT_EQ(collection.activeSubmap(), s1);
  {
    Submap::WriteLock lock = s1->lockForIntegration();
    lock.layer().allocateBlock(BlockIndex(0, 0, 0));
  }
  const auto s2 = collection.createSubmap(pose(0.3, {0, 0, 1}, {2, 0, 0}), 30, 3000);
  EXPECT_EQ(collection.submapIds(), (std::vector<SubmapId>{0, 1, 2}));
  EXPECT_EQ(collection.numBlocks(), 1u);
  EXPECT_EQ(collection.memoryBytes(),
            s0->layer().memoryBytes() + s1->layer().memoryBytes() + s2->layer().memoryBytes());
  EXPECT_EQ(collection.getSubmap(1), s1);
  EXPECT_EQ(collection.getSubmap(5), nullptr);

  const std::vector<SubmapPose> poses = collection.poseSnapshot();
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(poses[1].anchor_keyframe, 20);
  EXPECT_TRUE(poses[1].T_G_M.isApprox(s1->T_G_M(), 0.0));
  EXPECT_FALSE(poses[1].active);
  EXPECT_TRUE(poses[2].active);

  EXPECT_TRUE(collection.removeSubmap(1));
  EXPECT_FALSE(collection.removeSubmap(1));
  EXPECT_EQ(collection.submapIds(), (std::vector<SubmapId>{0, 2}));
  EXPECT_EQ(s1->numBlocks(), 1u);  // a holder keeps it alive
  EXPECT_EQ(collection.numBlocks(), 0u);
  // Removing the active submap finishes it; no active submap remains.
  EXPECT_TRUE(collection.removeSubmap(2));
  EXPECT_TRUE(s2->isFinished());
  EXPECT_EQ(collection.activeSubmap(), nullptr);
  // Ids are never reused.
  EXPECT_EQ(collection.createSubmap(Transformationd(), 40, 4000)->id(), 3);
  collection.finishActiveSubmap();
  EXPECT_EQ(collection.activeSubmap(), nullptr);
  EXPECT_THROW(collection.createSubmap(Transformationd(Eigen::Quaterniond(std::nan(""), 0, 0, 0),
                                                       Eigen::Vector3d::Zero()),
                                       50, 0),
               std::invalid_argument);
  EXPECT_EQ(collection.size(), 2u);
}

// restoreSubmap keeps the saved ids (ids only increase), takes over the layer without a copy,
// finishes finished submaps at once and makes an unfinished one active; snapshot() is
// consistent and reserveSubmapIds() keeps ids of removed submaps from being reused.
TEST(SubmapCollection, RestoreSubmapKeepsIdsLayersAndActiveState) {
  SubmapCollection collection(collectionConfig());
  TsdfLayer layer(collectionConfig().layer);
  layer.allocateBlock(BlockIndex(-3, 0, 7))->voxel(5) = TsdfVoxel{0.01f, 2.0f, Color{1, 2, 3}};
  const Block* block = layer.getBlock(BlockIndex(-3, 0, 7));
  const Transformationd P2 = pose(0.2, {0, 1, 0}, {1, 2, 3});
  const auto s2 = collection.restoreSubmap(2, std::move(layer), P2, 20, 2000, /*finished=*/true);
  EXPECT_EQ(s2->id(), 2);
  EXPECT_TRUE(s2->isFinished());
  EXPECT_EQ(s2->layer().getBlock(BlockIndex(-3, 0, 7)), block);  // moved, not copied
  EXPECT_EQ(s2->numBlocks(), 1u);
  EXPECT_EQ(s2->anchorKeyframe(), 20);
  EXPECT_EQ(s2->creationTimeNs(), 2000);
  EXPECT_TRUE(s2->T_G_M().isApprox(P2, 0.0));
  EXPECT_EQ(collection.activeSubmap(), nullptr);
  EXPECT_EQ(collection.nextSubmapId(), 3);

  const auto s5 = collection.restoreSubmap(5, TsdfLayer(collectionConfig().layer),
                                           Transformationd(), 50, 5000, /*finished=*/false);
  EXPECT_TRUE(s5->isActive());
  EXPECT_EQ(collection.activeSubmap(), s5);
  // Ids below the next one, another geometry, a non-finite pose: refused, nothing changes.
  EXPECT_THROW(collection.restoreSubmap(4, TsdfLayer(collectionConfig().layer), Transformationd(),
                                        1, 0, true),
               std::invalid_argument);
  EXPECT_THROW(
      collection.restoreSubmap(9, TsdfLayer(LayerConfig{0.05f, 8}), Transformationd(), 1, 0, true),
      std::invalid_argument);
  EXPECT_THROW(
      collection.restoreSubmap(
          9, TsdfLayer(collectionConfig().layer),
          Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(NAN, 0, 0)), 1, 0, true),
      std::invalid_argument);
  EXPECT_EQ(collection.submapIds(), (std::vector<SubmapId>{2, 5}));
  EXPECT_EQ(collection.nextSubmapId(), 6);

  // Anchored to its keyframe like a created submap.
  const Transformationd Q = pose(0.5, {1, 0, 0}, {0, 0, 1});
  EXPECT_EQ(collection.updateKeyframePoses({{20, Q}}).submaps_moved, 1u);
  EXPECT_TRUE(s2->T_G_M().isApprox(Q, 0.0));

  collection.reserveSubmapIds(8);
  collection.reserveSubmapIds(7);  // never lowers it
  const SubmapCollectionState state = collection.snapshot();
  EXPECT_EQ(state.next_submap_id, 8);
  EXPECT_EQ(state.active, s5);
  ASSERT_EQ(state.submaps.size(), 2u);
  EXPECT_EQ(state.submaps[0], s2);
  // A created submap continues after the reserved ids and finishes the restored active one.
  EXPECT_EQ(collection.createSubmap(Transformationd(), 80, 8000)->id(), 8);
  EXPECT_TRUE(s5->isFinished());
}

// updateKeyframePoses moves exactly the submaps anchored to the batch's keyframes; known
// non-anchor keyframes move nothing; unknown ids and non-finite poses are ignored and
// counted.
TEST(SubmapCollection, UpdateKeyframePosesMovesOnlyAnchoredSubmaps) {
  SubmapCollection collection(collectionConfig());
  const Transformationd P0 = pose(0.1, {0, 0, 1}, {0, 0, 0});
  const Transformationd P1 = pose(0.2, {0, 1, 0}, {1, 0, 0});
  const Transformationd P2 = pose(0.3, {1, 0, 0}, {2, 0, 0});
  collection.createSubmap(P0, 10, 0);
  collection.createSubmap(P1, 20, 0)->addKeyframe(21);
  collection.createSubmap(P2, 30, 0);

  const Transformationd Q1 = pose(-0.4, {1, 2, 3}, {0.3, 0.2, 0.1});
  const Transformationd nan_pose(Eigen::Quaterniond::Identity(),
                                 Eigen::Vector3d(0, std::nan(""), 0));
  const KeyframePoseUpdateResult result = collection.updateKeyframePoses(
      {{20, Q1}, {21, pose(1.0, {0, 0, 1}, {5, 5, 5})}, {99, Q1}, {30, nan_pose}});
  EXPECT_EQ(result.submaps_moved, 1u);
  EXPECT_EQ(result.keyframes_known, 2u);    // 20 (anchor) and 21 (contributor)
  EXPECT_EQ(result.keyframes_unknown, 1u);  // 99
  EXPECT_EQ(result.poses_invalid, 1u);      // 30 with NaN
  EXPECT_TRUE(collection.getSubmap(0)->T_G_M().isApprox(P0, 0.0));
  EXPECT_TRUE(collection.getSubmap(1)->T_G_M().isApprox(Q1, 0.0));
  EXPECT_TRUE(collection.getSubmap(2)->T_G_M().isApprox(P2, 0.0));

  // Two submaps anchored to the same keyframe both move; the last entry wins.
  collection.createSubmap(P2, 10, 0);
  const KeyframePoseUpdateResult again = collection.updateKeyframePoses({{10, Q1}, {10, P1}});
  EXPECT_EQ(again.submaps_moved, 4u);
  EXPECT_TRUE(collection.getSubmap(0)->T_G_M().isApprox(P1, 0.0));
  EXPECT_TRUE(collection.getSubmap(3)->T_G_M().isApprox(P1, 0.0));
  // After removal the anchor is unknown.
  collection.removeSubmap(2);
  EXPECT_EQ(collection.updateKeyframePoses({{30, Q1}}).keyframes_unknown, 1u);
}

// The home of a keyframe is the oldest submap that records it, as anchor or contributor.
TEST(SubmapCollection, OldestSubmapWithKeyframe) {
  SubmapCollection collection(collectionConfig());
  const Transformationd P0 = pose(0.1, {0, 0, 1}, {0, 0, 0});
  const Transformationd P1 = pose(0.2, {0, 1, 0}, {1, 0, 0});
  collection.createSubmap(P0, 10, 0)->addKeyframe(11);
  collection.createSubmap(P1, 20, 0);
  collection.createSubmap(P0, 10, 0)->addKeyframe(21);  // shares anchor 10 with submap 0
  EXPECT_FALSE(collection.oldestSubmapWithKeyframe(99).has_value());
  const std::optional<SubmapPose> home = collection.oldestSubmapWithKeyframe(10);
  ASSERT_TRUE(home.has_value());
  EXPECT_EQ(home->id, 0);
  EXPECT_EQ(home->anchor_keyframe, 10);
  EXPECT_TRUE(home->T_G_M.isApprox(P0, 0.0));
  EXPECT_FALSE(home->active);
  EXPECT_EQ(collection.oldestSubmapWithKeyframe(11)->id, 0);
  EXPECT_EQ(collection.oldestSubmapWithKeyframe(21)->id, 2);
  EXPECT_EQ(collection.oldestSubmapWithKeyframe(20)->anchor_keyframe, 20);
  collection.removeSubmap(0);
  EXPECT_EQ(collection.oldestSubmapWithKeyframe(10)->id, 2);
  EXPECT_TRUE(collection.oldestSubmapWithKeyframe(10)->active);
}

// Moving a submap moves its mesh exactly: the global mesh after the anchor keyframe's pose
// changes from A to B equals the old global mesh transformed by B A^-1 (vertex-wise within
// 1e-5 m), and no voxel changes.
TEST(SubmapCollection, MovingTheAnchorMovesTheMeshExactly) {
  const std::vector<SyntheticFrame> frames = test::renderOrbit(6);
  SubmapCollection collection(collectionConfig());
  const Transformationd A = pose(0.4, {1, 2, 3}, {0.3, -0.2, 0.1});
  const Transformationd B = pose(-0.7, {0.2, 1, -0.5}, {1.5, 0.8, -0.4});
  const std::shared_ptr<Submap> submap = collection.createSubmap(A, 7, 0);
  test::integrateFrames(submap.get(), frames, 0, frames.size());
  collection.finishActiveSubmap();
  ASSERT_GT(submap->numBlocks(), 100u);

  const auto voxels_before = test::layerVoxels(submap->layer());
  const Mesh mesh_M = test::meshLayer(submap->layer());
  ASSERT_GT(mesh_M.numVertices(), 1000u);
  const Mesh mesh_G_before = transformMesh(submap->T_G_M().cast<float>(), mesh_M);
  // The integrated surface is where the scene is (sanity check of T_M_C).
  EXPECT_LT(test::vertexRmse(mesh_G_before, makeSphereScene()), 0.5 * test::kVoxelSize);

  const KeyframePoseUpdateResult result = collection.updateKeyframePoses({{7, B}});
  EXPECT_EQ(result.submaps_moved, 1u);
  EXPECT_TRUE(test::sameVoxels(test::layerVoxels(submap->layer()), voxels_before));

  const Mesh mesh_G_after =
      transformMesh(submap->T_G_M().cast<float>(), test::meshLayer(submap->layer()));
  const Mesh expected = transformMesh((B * A.inverse()).cast<float>(), mesh_G_before);
  ASSERT_EQ(mesh_G_after.numVertices(), expected.numVertices());
  ASSERT_EQ(mesh_G_after.triangles, expected.triangles);
  float max_error = 0.0f;
  for (size_t i = 0; i < expected.numVertices(); ++i) {
    max_error = std::max(max_error, (mesh_G_after.vertices[i] - expected.vertices[i]).norm());
  }
  EXPECT_LT(max_error, 1e-5f);
  std::printf("[ measured ] %zu vertices, max vertex displacement error %.3g m\n",
              expected.numVertices(), static_cast<double>(max_error));
}

}  // namespace
}  // namespace cblox
