#include "core/mapping/planning_map.h"

#include <atomic>
#include <cmath>
#include <span>
#include <thread>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "core/mapping/planning_config.h"
#include "test/esdf/esdf_test_scenes.h"

namespace cblox {
namespace {

constexpr float kVoxel = 0.05f;
constexpr float kTruncation = 0.15f;

SubmapCollectionConfig collectionConfig() {
  SubmapCollectionConfig config;
  config.layer.voxel_size = kVoxel;
  config.layer.voxels_per_side = 8;
  return config;
}

EsdfConfig fieldConfig() {
  EsdfConfig config;
  config.max_distance_m = 1.0f;
  return config;
}

Transformationd translation(double x, double y, double z) {
  return Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(x, y, z));
}

/// Two subvolumes, written before any thread runs (so the test may write their layers):
/// 0 at the origin holds a wall x < 0.31 (in its frame) over [-0.4, 1.6] x [-0.4, 0.4]^2;
/// 1 at (0, 3, 0) holds the same observed volume with a ball of radius 0.2 at (1, 0, 0).
class PlanningMapTest : public ::testing::Test {
 protected:
  void SetUp() override {
    wall_ = collection_.createSubmap(Transformationd(), 0, 0);
    esdf_test::writeTsdf(wall_->mutableLayer(), esdf_test::planeX(0.31f), lo_, hi_, kTruncation);
    ball_ = collection_.createSubmap(translation(0.0, 3.0, 0.0), 1, 1);
    esdf_test::writeTsdf(ball_->mutableLayer(),
                         esdf_test::ball(Eigen::Vector3f(1.0f, 0.0f, 0.0f), 0.2f), lo_, hi_,
                         kTruncation);
    wall_->refreshStatistics();
    ball_->refreshStatistics();
  }
  const Eigen::Vector3f lo_{-0.4f, -0.4f, -0.4f}, hi_{1.6f, 0.4f, 0.4f};
  SubmapCollection collection_{collectionConfig()};
  std::shared_ptr<Submap> wall_, ball_;
  PlanningMap planning_{fieldConfig()};
};

TEST_F(PlanningMapTest, AnswersInTheGlobalFrameThroughEachSubvolumesPose) {
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  const PlanningMapStats stats = planning_.stats();
  EXPECT_EQ(stats.fields, 2u);
  EXPECT_EQ(stats.blocks, wall_->numBlocks() + ball_->numBlocks());
  EXPECT_GT(stats.memory_bytes, stats.blocks * 512 * sizeof(EsdfVoxel));
  EXPECT_EQ(planning_.memoryBytes(), stats.memory_bytes);

  // The wall: exact (straight sites), unit gradient along +x.
  const DistanceAnswer near_wall = planning_.query({0.72, 0.013, -0.02});
  ASSERT_EQ(near_wall.state, VoxelState::kFree);
  EXPECT_NEAR(near_wall.distance, 0.72 - 0.31, 1e-5);
  ASSERT_TRUE(near_wall.has_gradient);
  EXPECT_NEAR(near_wall.gradient.x(), 1.0, 1e-4);
  EXPECT_EQ(near_wall.submap, static_cast<int64_t>(wall_->id()));
  // The ball, 3 m along y in G: within a voxel of the exact distance.
  const DistanceAnswer near_ball = planning_.query({1.5, 3.02, 0.03});
  ASSERT_EQ(near_ball.state, VoxelState::kFree);
  const double truth = (Eigen::Vector3d(1.5, 0.02, 0.03) - Eigen::Vector3d(1, 0, 0)).norm() - 0.2;
  EXPECT_NEAR(near_ball.distance, truth, kVoxel);
  EXPECT_EQ(near_ball.submap, static_cast<int64_t>(ball_->id()));
  const DistanceAnswer inside = planning_.query({1.0, 3.0, 0.0});
  EXPECT_EQ(inside.state, VoxelState::kUnknown);  // deeper than the truncation: unobserved
  const DistanceAnswer surface = planning_.query({1.19, 3.0, 0.0});
  EXPECT_EQ(surface.state, VoxelState::kOccupied);
  EXPECT_LE(surface.distance, 0.0);
  // Nobody observed the space between the two subvolumes.
  const DistanceAnswer between = planning_.query({0.5, 1.5, 0.0});
  EXPECT_EQ(between.state, VoxelState::kUnknown);
  EXPECT_TRUE(std::isnan(between.distance));
  EXPECT_EQ(between.submap, -1);
  EXPECT_EQ(planning_.query({NAN, 0.0, 0.0}).state, VoxelState::kUnknown);
}

TEST_F(PlanningMapTest, FreeAnswersBesideAnObstacleAreLoweredByTheMargin) {
  // The wall x < 0.31 is exact at every point (straight sites, linear interpolation). With
  // the default margin of half a voxel: lowered by half a voxel up to 1.5 voxels, by less
  // over the next voxel (the gradient 1.5 times steeper there), never below 0.
  ASSERT_EQ(fieldConfig().surface_margin_voxels, 0.5f);
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  EsdfConfig raw_config = fieldConfig();
  raw_config.surface_margin_voxels = 0.0f;
  PlanningMap raw(raw_config);
  raw.refresh(collection_, PlanningMap::Scope::kAll);
  struct Case {
    double voxels;    // exact distance to the wall
    double answered;  // voxels
    double slope;
  };
  for (const Case& c : {Case{0.4, 0.0, 1.0}, Case{1.0, 0.5, 1.0}, Case{1.4, 0.9, 1.0},
                        Case{2.0, 1.75, 1.5}, Case{2.6, 2.6, 1.0}, Case{8.2, 8.2, 1.0}}) {
    SCOPED_TRACE(c.voxels);
    const Eigen::Vector3d p(0.31 + c.voxels * kVoxel, 0.013, -0.02);
    const DistanceAnswer a = planning_.query(p);
    ASSERT_EQ(a.state, VoxelState::kFree);
    EXPECT_NEAR(a.distance, c.answered * kVoxel, 1e-5);
    ASSERT_TRUE(a.has_gradient);
    EXPECT_NEAR(a.gradient.x(), c.slope, 1e-4);
    const DistanceAnswer r = raw.query(p);
    EXPECT_NEAR(r.distance, c.voxels * kVoxel, 1e-5);
    EXPECT_NEAR(r.gradient.x(), 1.0, 1e-4);
  }
  // Occupied answers keep their value.
  EXPECT_EQ(planning_.query({0.29, 0.0, 0.0}).distance, raw.query({0.29, 0.0, 0.0}).distance);
}

TEST_F(PlanningMapTest, APoseBatchMovesTheAnswersWithoutRecomputingAField) {
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  const uint64_t updates = planning_.stats().updates;
  const Eigen::Vector3d p(1.45, 3.1, -0.05);
  const DistanceAnswer before = planning_.query(p);
  ASSERT_EQ(before.state, VoxelState::kFree);
  // A loop closure moves subvolume 1 by (0.2, -0.1, 0) and turns it 90 degrees about z
  // around its origin.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Transformationd moved(R, Eigen::Vector3d(0.2, 2.9, 0.0));
  ASSERT_TRUE(ball_->setT_G_M(moved));
  planning_.setPoses(collection_.poseSnapshot());
  EXPECT_EQ(planning_.stats().updates, updates);
  // The same point of the subvolume, where it is now.
  const Eigen::Vector3d p_M = translation(0.0, 3.0, 0.0).inverse() * p;
  const DistanceAnswer after = planning_.query(moved * p_M);
  ASSERT_EQ(after.state, VoxelState::kFree);
  EXPECT_NEAR(after.distance, before.distance, 1e-5);
  ASSERT_TRUE(before.has_gradient && after.has_gradient);
  EXPECT_LT((after.gradient - R * before.gradient).norm(), 1e-4);
}

TEST_F(PlanningMapTest, OverlappingSubvolumesAnswerTheNearestObstacleAndOccupiedWins) {
  // Subvolume 1 moved onto subvolume 0: both observe the same space.
  ASSERT_TRUE(ball_->setT_G_M(Transformationd()));
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  // Near the ball, the wall is farther: the ball's subvolume answers.
  const DistanceAnswer a = planning_.query({1.3, 0.0, 0.0});
  ASSERT_EQ(a.state, VoxelState::kFree);
  EXPECT_NEAR(a.distance, 0.1, kVoxel);
  EXPECT_EQ(a.submap, static_cast<int64_t>(ball_->id()));
  // Inside the wall's obstacle, where the ball's subvolume saw free space: occupied.
  const DistanceAnswer b = planning_.query({0.29, 0.0, 0.0});
  EXPECT_EQ(b.state, VoxelState::kOccupied);
  EXPECT_EQ(b.submap, static_cast<int64_t>(wall_->id()));
  // A batch gives the same answers as single queries.
  const std::vector<Eigen::Vector3d> points = {{1.3, 0.0, 0.0}, {0.29, 0.0, 0.0}, {9, 9, 9}};
  std::vector<DistanceAnswer> answers;
  planning_.queryBatch(points, &answers);
  ASSERT_EQ(answers.size(), 3u);
  EXPECT_EQ(answers[0].distance, a.distance);
  EXPECT_EQ(answers[1].state, VoxelState::kOccupied);
  EXPECT_EQ(answers[2].state, VoxelState::kUnknown);
}

TEST_F(PlanningMapTest, AnotherSubvolumesObstacleBoundsAFreeAnswerBesideItsBlocks) {
  // Subvolume 2 observed free space (no obstacle within its cap) beside the wall's blocks,
  // which end at y = 0.8: the wall's subvolume never observed it.
  const std::shared_ptr<Submap> open = collection_.createSubmap(Transformationd(), 2, 2);
  esdf_test::writeTsdf(open->mutableLayer(), esdf_test::planeX(-5.0f), {-0.4f, 0.85f, -0.4f},
                       {1.59f, 1.55f, 0.39f}, kTruncation);
  open->refreshStatistics();
  const Eigen::Vector3d p(0.5, 0.9, 0.0);
  // Without a band only the subvolume that observed the point answers: the cap.
  PlanningMap unbanded(fieldConfig());
  unbanded.refresh(collection_, PlanningMap::Scope::kAll);
  const DistanceAnswer far = unbanded.query(p);
  ASSERT_EQ(far.state, VoxelState::kFree);
  EXPECT_FLOAT_EQ(far.distance, 1.0);
  EXPECT_EQ(far.submap, static_cast<int64_t>(open->id()));
  // With one ring of band blocks the wall's field carries its obstacle there. The wall's
  // observed edge (0.31, 0.8) is 0.215 m away; the voxels around p hold 0.23-0.28 through
  // the surface voxels' centres, so the answer is within a voxel of it.
  EsdfConfig banded_config = fieldConfig();
  banded_config.band_blocks = 1;
  PlanningMap banded(banded_config);
  banded.refresh(collection_, PlanningMap::Scope::kAll);
  const DistanceAnswer near = banded.query(p);
  ASSERT_EQ(near.state, VoxelState::kFree);  // still observed free space
  EXPECT_GT(near.distance, 0.215);
  EXPECT_LT(near.distance, 0.215 + kVoxel);
  EXPECT_EQ(near.submap, static_cast<int64_t>(wall_->id()));
  ASSERT_TRUE(near.has_gradient);  // away from the wall's edge: +x, +y
  EXPECT_GT(near.gradient.x(), 0.3);
  EXPECT_GT(near.gradient.y(), 0.3);
  // Unknown space stays unknown whatever obstacle is known near it; the band is no
  // observation and does not widen the map's bounds.
  EXPECT_EQ(banded.query({0.5, 1.9, 0.0}).state, VoxelState::kUnknown);
  EXPECT_EQ(banded.query({0.5, 1.0, 0.6}).state, VoxelState::kUnknown);
  EXPECT_TRUE(banded.boundsG().isApprox(unbanded.boundsG()));
  EXPECT_EQ(banded.stats().blocks - banded.stats().band_blocks, unbanded.stats().blocks);
  EXPECT_GT(banded.stats().band_blocks, 0u);
  EXPECT_EQ(unbanded.stats().band_blocks, 0u);
  // A memory cap's projection for twice the TSDF blocks: twice the fields' blocks, band
  // included (a working block and a snapshot record each).
  const size_t tsdf_blocks = wall_->numBlocks() + ball_->numBlocks() + open->numBlocks();
  const size_t per_block = 2 * sizeof(EsdfBlock) + 512 * sizeof(EsdfVoxel);
  const size_t projected =
      banded.projectedBytes(2 * tsdf_blocks, collectionConfig().layer) - banded.workingBytes();
  EXPECT_LE(projected, 2 * banded.stats().blocks * per_block);
  EXPECT_GE(projected, (2 * banded.stats().blocks - 1) * per_block);
  EXPECT_EQ(unbanded.projectedBytes(2 * tsdf_blocks, collectionConfig().layer) -
                unbanded.workingBytes(),
            2 * tsdf_blocks * per_block);
}

TEST_F(PlanningMapTest, FollowsChangedAndRemovedSubvolumes) {
  // The periodic scope leaves the active subvolume (1) alone: no field, its space unknown.
  planning_.refresh(collection_, PlanningMap::Scope::kFinished);
  EXPECT_EQ(planning_.stats().fields, 1u);
  EXPECT_EQ(planning_.query({1.5, 3.02, 0.03}).state, VoxelState::kUnknown);
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  const size_t bytes_both = planning_.memoryBytes();
  // A fusion-like change of finished subvolume 0: its wall moves to x < 0.51.
  esdf_test::writeTsdf(wall_->mutableLayer(), esdf_test::planeX(0.51f), lo_, hi_, kTruncation);
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  EXPECT_NEAR(planning_.query({0.92, 0.0, 0.0}).distance, 0.92 - 0.51, 1e-5);
  // Unchanged subvolumes are not computed again.
  const uint64_t updates = planning_.stats().updates;
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  EXPECT_EQ(planning_.stats().updates, updates);
  // Subvolume 1 is removed (fused away): its field and its bytes go.
  ASSERT_TRUE(collection_.removeSubmap(ball_->id()));
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  EXPECT_EQ(planning_.stats().fields, 1u);
  EXPECT_LT(planning_.memoryBytes(), bytes_both);
  EXPECT_EQ(planning_.query({1.5, 3.02, 0.03}).state, VoxelState::kUnknown);
}

TEST_F(PlanningMapTest, TheActiveSubvolumesFieldFollowsItsLayerAlone) {
  // refreshActive computes subvolume 1 (active) only, and only when its layer changed.
  ASSERT_TRUE(ball_->isActive());
  planning_.refreshActive(collection_);
  EXPECT_EQ(planning_.stats().fields, 1u);
  EXPECT_EQ(planning_.query({0.72, 0.0, 0.0}).state, VoxelState::kUnknown);  // the wall's
  const DistanceAnswer near_ball = planning_.query({1.5, 3.02, 0.03});
  ASSERT_EQ(near_ball.state, VoxelState::kFree);
  const uint64_t updates = planning_.stats().updates;
  planning_.refreshActive(collection_);
  EXPECT_EQ(planning_.stats().updates, updates);
  // The ball grows (integration writes the active layer and bumps its revision).
  {
    Submap::WriteLock lock = ball_->lockForIntegration();
    ASSERT_TRUE(lock);
    esdf_test::writeTsdf(&lock.layer(), esdf_test::ball(Eigen::Vector3f(1.0f, 0.0f, 0.0f), 0.3f),
                         lo_, hi_, kTruncation);
  }
  planning_.refreshActive(collection_);
  EXPECT_EQ(planning_.stats().updates, updates + 1);
  const double truth = (Eigen::Vector3d(1.5, 0.02, 0.03) - Eigen::Vector3d(1, 0, 0)).norm() - 0.3;
  EXPECT_NEAR(planning_.query({1.5, 3.02, 0.03}).distance, truth, kVoxel);
  // Once finished, it is the worker's: refreshActive leaves it.
  collection_.finishActiveSubmap();
  esdf_test::writeTsdf(ball_->mutableLayer(), esdf_test::empty(), lo_, hi_, kTruncation);
  planning_.refreshActive(collection_);
  EXPECT_EQ(planning_.stats().updates, updates + 1);
}

TEST_F(PlanningMapTest, QueriesBesideRefreshesSeeWholeFields) {
  // The active ball alternates between radius 0.2 and 0.3 while another thread queries a
  // point near it: every answer is one of the two fields', never a field half way through
  // its waves (a raise wave clears distances before the lower wave refills them).
  const Eigen::Vector3d p(1.5, 3.02, 0.03);
  const auto grow = [this](float radius) {
    Submap::WriteLock lock = ball_->lockForIntegration();
    ASSERT_TRUE(lock);
    esdf_test::writeTsdf(&lock.layer(), esdf_test::ball(Eigen::Vector3f(1.0f, 0.0f, 0.0f), radius),
                         lo_, hi_, kTruncation);
  };
  planning_.refreshActive(collection_);
  const double small = planning_.query(p).distance;
  grow(0.3f);
  planning_.refreshActive(collection_);
  const double large = planning_.query(p).distance;
  ASSERT_GT(small - large, 1.5 * kVoxel);
  std::atomic<bool> done{false};
  std::atomic<int> queries{0}, torn{0};
  std::thread reader([&] {
    while (!done.load()) {
      const DistanceAnswer a = planning_.query(p);
      if (a.state != VoxelState::kFree ||
          (std::abs(a.distance - small) > 0.2 * kVoxel &&
           std::abs(a.distance - large) > 0.2 * kVoxel)) {
        torn.fetch_add(1);
      }
      queries.fetch_add(1);
    }
  });
  for (int i = 0; i < 20; ++i) {
    grow(i % 2 == 0 ? 0.2f : 0.3f);
    planning_.refreshActive(collection_);
  }
  while (queries.load() < 100) std::this_thread::yield();
  done = true;
  reader.join();
  EXPECT_EQ(torn.load(), 0) << "of " << queries.load() << " answers";
  EXPECT_NEAR(planning_.query(p).distance, large, 0.2 * kVoxel);
}

TEST_F(PlanningMapTest, ABatchSplitOverThreadsGivesTheSameAnswers) {
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  // Points over both subvolumes and the unknown space around them.
  std::vector<Eigen::Vector3d> points;
  for (double x = -0.5; x <= 1.7; x += 0.07) {
    for (double y = -0.5; y <= 3.5; y += 0.09) {
      for (double z = -0.3; z <= 0.3; z += 0.2) points.emplace_back(x, y, z);
    }
  }
  ASSERT_GT(points.size(), 3 * PlanningMap::kMinPointsPerThread);
  std::vector<DistanceAnswer> one, three;
  planning_.queryBatch(points, &one, 1);
  planning_.queryBatch(points, &three, 3);
  ASSERT_EQ(three.size(), points.size());
  size_t known = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(three[i].state, one[i].state) << i;
    ASSERT_EQ(three[i].submap, one[i].submap) << i;
    if (one[i].state == VoxelState::kUnknown) continue;
    ++known;
    ASSERT_EQ(three[i].distance, one[i].distance) << i;
    ASSERT_EQ(three[i].has_gradient, one[i].has_gradient) << i;
  }
  EXPECT_GT(known, points.size() / 10);
  // A batch too small to split: still every answer.
  planning_.queryBatch(std::span<const Eigen::Vector3d>(points.data(), 7), &three, 3);
  ASSERT_EQ(three.size(), 7u);
  for (size_t i = 0; i < 7; ++i) EXPECT_EQ(three[i].state, one[i].state);
}

TEST_F(PlanningMapTest, ALocalGridHoldsTheAnswersAtItsCellCentres) {
  planning_.refresh(collection_, PlanningMap::Scope::kAll);
  LocalGrid grid;
  std::string error;
  ASSERT_TRUE(planning_.localGrid({0.0, -0.2, -0.1}, {1.0, 0.2, 0.1}, 0.1, &grid, &error))
      << error;
  EXPECT_EQ(grid.size, Eigen::Vector3i(10, 4, 2));
  ASSERT_EQ(grid.state.size(), 80u);
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 10; ++i) {
        const DistanceAnswer a = planning_.query(grid.cellCenter(i, j, k));
        ASSERT_EQ(grid.state[grid.index(i, j, k)], a.state);
        if (a.state != VoxelState::kUnknown) {
          EXPECT_EQ(grid.distance[grid.index(i, j, k)], static_cast<float>(a.distance));
        }
      }
    }
  }
  EXPECT_EQ(grid.state[grid.index(9, 0, 0)], VoxelState::kFree);  // x = 0.95
  EXPECT_NEAR(grid.distance[grid.index(9, 0, 0)], 0.95 - 0.31, 1e-5);
  EXPECT_TRUE(planning_.isObserved({0.95, 0.0, 0.0}));
  EXPECT_FALSE(planning_.isObserved({0.5, 1.5, 0.0}));

  // Refusals, before anything is allocated.
  LocalGrid untouched;
  EXPECT_FALSE(planning_.localGrid({0, 0, 0}, {1, 1, 1}, 0.0, &untouched, &error));
  EXPECT_NE(error.find("resolution"), std::string::npos);
  EXPECT_FALSE(planning_.localGrid({0, 0, 0}, {1, 1, NAN}, 0.1, &untouched, &error));
  EXPECT_FALSE(planning_.localGrid({0, 0, 0}, {1, -1, 1}, 0.1, &untouched, &error));
  EXPECT_FALSE(planning_.localGrid({-1e6, -1e6, -1e6}, {1e6, 1e6, 1e6}, 0.01, &untouched, &error));
  EXPECT_NE(error.find("cells"), std::string::npos);
  EXPECT_TRUE(untouched.state.empty());
}

TEST(PlanningMapConfigTest, RefusesABadField) {
  EsdfConfig bad;
  bad.max_distance_m = -1.0f;
  EXPECT_THROW(PlanningMap{bad}, std::invalid_argument);
  EsdfConfig auto_band;
  auto_band.band_blocks = PlanningConfig::kBandAuto;  // a PlanningConfig value, unresolved
  EXPECT_THROW(PlanningMap{auto_band}, std::invalid_argument);
}

TEST(PlanningMapConfigTest, TheAutomaticBandFollowsCarving) {
  PlanningConfig config;
  EXPECT_EQ(config.esdf.band_blocks, PlanningConfig::kBandAuto);
  EXPECT_EQ(config.validate(), "");
  EXPECT_EQ(config.bandBlocks(0.0), 0);
  EXPECT_EQ(config.bandBlocks(3.0), 1);
  config.esdf.band_blocks = 2;
  EXPECT_EQ(config.bandBlocks(0.0), 2);
  config.esdf.band_blocks = 0;
  EXPECT_EQ(config.bandBlocks(3.0), 0);
  config.esdf.band_blocks = 3;
  EXPECT_NE(config.validate().find("planning.band_blocks"), std::string::npos);
}

}  // namespace
}  // namespace cblox
