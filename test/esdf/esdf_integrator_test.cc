#include "core/esdf/esdf_integrator.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/esdf/esdf_query.h"
#include "test/esdf/esdf_test_scenes.h"

namespace cblox {
namespace {

using esdf_test::Sdf;

constexpr float kVoxel = 0.05f;
constexpr float kTruncation = 0.15f;

LayerConfig geometry() {
  LayerConfig config;
  config.voxel_size = kVoxel;
  config.voxels_per_side = 8;
  return config;
}

EsdfConfig fieldConfig(float max_distance = 1.0f) {
  EsdfConfig config;
  config.max_distance_m = max_distance;
  return config;
}

struct Errors {
  std::vector<float> voxels;  // |field - truth| / voxel size, free voxels nearer than the cap
  float quantile(double q) const {
    if (voxels.empty()) return 0.0f;
    std::vector<float> sorted = voxels;
    std::sort(sorted.begin(), sorted.end());
    return sorted[static_cast<size_t>(q * static_cast<double>(sorted.size() - 1))];
  }
  float max() const {
    return voxels.empty() ? 0.0f : *std::max_element(voxels.begin(), voxels.end());
  }
};

/// Compares every observed voxel of `esdf` with the exact signed distance: occupied voxels
/// must hold their TSDF value, free voxels within the cap are collected as errors, free voxels
/// beyond it must say the cap.
Errors compare(const EsdfLayer& esdf, const Sdf& sdf) {
  Errors errors;
  for (const auto& [key, block] : esdf.blocks()) {
    for (int i = 0; i < esdf.voxelsPerBlock(); ++i) {
      const GridIndex local(i & 7, (i >> 3) & 7, i >> 6);
      const GlobalVoxelIndex global = block->index * 8 + local;
      VoxelState state;
      float distance;
      EXPECT_TRUE(voxelDistance(esdf, global, &state, &distance));
      if (state != VoxelState::kFree) continue;
      const float truth = sdf(esdf.globalVoxelCenter(global));
      if (truth < esdf.maxDistance() - kVoxel) {
        errors.voxels.push_back(std::abs(distance - truth) / kVoxel);
      } else if (truth > esdf.maxDistance() + 2 * kVoxel) {
        EXPECT_EQ(distance, esdf.maxDistance());
      }
    }
  }
  return errors;
}

TEST(EsdfIntegratorTest, APlaneGivesExactDistancesUpToTheCap) {
  TsdfLayer tsdf(geometry());
  const Sdf plane = esdf_test::planeX(0.31f);
  esdf_test::writeTsdf(&tsdf, plane, {-0.4f, -0.4f, -0.4f}, {1.6f, 0.4f, 0.4f}, kTruncation);
  EsdfLayer esdf(geometry(), 1.0f);
  EsdfIntegrator integrator(fieldConfig());
  const EsdfUpdateStats stats = integrator.update(tsdf, &esdf);
  EXPECT_EQ(stats.esdf_blocks_added, tsdf.numBlocks());
  EXPECT_EQ(stats.tsdf_blocks_read, tsdf.numBlocks());
  EXPECT_FALSE(stats.rebuilt);
  EXPECT_EQ(esdf.numBlocks(), tsdf.numBlocks());
  // The nearest site of a free voxel lies straight along x: |x - s| + tsdf(s) = x - 0.31.
  const Errors errors = compare(esdf, plane);
  ASSERT_GT(errors.voxels.size(), 5000u);
  EXPECT_LT(errors.max(), 1e-4f);
  // Occupied voxels hold their TSDF value; deep interior voxels are unknown.
  VoxelState state;
  float distance;
  ASSERT_TRUE(voxelDistance(esdf, GlobalVoxelIndex(5, 0, 0), &state, &distance));  // x=0.275
  EXPECT_EQ(state, VoxelState::kOccupied);
  EXPECT_FLOAT_EQ(distance, 0.275f - 0.31f);
  ASSERT_TRUE(voxelDistance(esdf, GlobalVoxelIndex(-3, 0, 0), &state, &distance));  // x=-0.125
  EXPECT_EQ(state, VoxelState::kUnknown);
}

TEST(EsdfIntegratorTest, ABallAndABoxStayWithinAFractionOfAVoxel) {
  const Sdf ball = esdf_test::ball({0.512f, 0.487f, 0.503f}, 0.33f);
  const Sdf box = esdf_test::box({-0.27f, -0.33f, -0.21f}, {0.13f, 0.02f, 0.24f});
  for (const Sdf& shape : {ball, box}) {
    TsdfLayer tsdf(geometry());
    esdf_test::writeTsdf(&tsdf, shape, {-0.9f, -0.9f, -0.9f}, {1.5f, 1.5f, 1.5f}, kTruncation);
    EsdfLayer esdf(geometry(), 1.0f);
    EsdfIntegrator integrator(fieldConfig());
    integrator.update(tsdf, &esdf);
    const Errors errors = compare(esdf, shape);
    ASSERT_GT(errors.voxels.size(), 10000u);
    // Sites on both sides of the surface put one within half a voxel diagonal of every
    // surface point; the brushfire carries each voxel the best site its neighbours offer.
    EXPECT_LT(errors.quantile(0.5), 0.1f);
    EXPECT_LT(errors.quantile(0.99), 0.35f);
    EXPECT_LT(errors.max(), 0.5f);
  }
}

TEST(EsdfIntegratorTest, SurfaceVoxelsOnBothSidesAnswerTheirTsdfDistance) {
  TsdfLayer tsdf(geometry());
  const Sdf ball = esdf_test::ball({0.512f, 0.487f, 0.503f}, 0.33f);
  esdf_test::writeTsdf(&tsdf, ball, {-0.5f, -0.5f, -0.5f}, {1.5f, 1.5f, 1.5f}, kTruncation);
  EsdfLayer esdf(geometry(), 1.0f);
  EsdfIntegrator(fieldConfig()).update(tsdf, &esdf);
  // Within one voxel of the surface, on either side, a voxel is a site and answers its own
  // TSDF value: exact for this exact TSDF inside; on the free side divided by the TSDF's
  // gradient norm where above 1 (differences over the curved surface: at most 0.05 voxel
  // below, never above). Deeper inside, occupied voxels answer theirs too.
  int sites = 0, deep = 0;
  for (const auto& [key, block] : esdf.blocks()) {
    for (int i = 0; i < esdf.voxelsPerBlock(); ++i) {
      const GlobalVoxelIndex global = block->index * 8 + GridIndex(i & 7, (i >> 3) & 7, i >> 6);
      VoxelState state;
      float distance;
      ASSERT_TRUE(voxelDistance(esdf, global, &state, &distance));
      const float truth = ball(esdf.globalVoxelCenter(global));
      if (std::abs(truth) < kVoxel) {
        EXPECT_TRUE(block->voxel(i).isSite());
        EXPECT_EQ(state, truth <= 0.0f ? VoxelState::kOccupied : VoxelState::kFree);
        if (truth <= 0.0f) {
          EXPECT_NEAR(distance, truth, 1e-6f);
        } else {
          EXPECT_LE(distance, truth + 1e-6f);
          EXPECT_GE(distance, truth - 0.05f * kVoxel);
        }
        ++sites;
      } else if (truth < 0.0f && truth >= -kTruncation) {
        EXPECT_EQ(state, VoxelState::kOccupied);
        EXPECT_NEAR(distance, truth, 1e-6f);
        ++deep;
      }
    }
  }
  EXPECT_GT(sites, 500);
  EXPECT_GT(deep, 500);
}

/// Per-voxel comparison of an incrementally updated field with a rebuilt one: the same
/// states everywhere, distances within `tolerance` voxels.
/// The integrator's contract that queries read: after an update, every voxel that carries a
/// site holds what that site gives now, |x - s| + max(tsdf(s), -voxel) (at least 0), and
/// its site is a site.
void expectDistancesFollowTheirSites(const EsdfLayer& esdf) {
  size_t checked = 0;
  for (const auto& [key, block] : esdf.blocks()) {
    for (int i = 0; i < esdf.voxelsPerBlock(); ++i) {
      const EsdfVoxel& v = block->voxel(i);
      if (!v.hasSite() || v.isSite()) continue;
      const GlobalVoxelIndex global = block->index * 8 + GridIndex(i & 7, (i >> 3) & 7, i >> 6);
      const Eigen::Vector3i offset(v.site[0], v.site[1], v.site[2]);
      const EsdfVoxel* site = esdf.getVoxel(global + offset);
      ASSERT_NE(site, nullptr) << global.transpose();
      ASSERT_TRUE(site->isSite()) << global.transpose();
      const float gives = std::max(
          0.0f, offset.cast<float>().norm() * kVoxel + std::max(site->own_distance, -kVoxel));
      ASSERT_NEAR(std::min(v.own_distance, esdf.maxDistance()), std::min(gives, esdf.maxDistance()),
                  1e-5f)
          << global.transpose();
      ++checked;
    }
  }
  EXPECT_GT(checked, 0u);
}

/// Same blocks, states, and distances within `tolerance` voxels; `incremental` may also be
/// below `rebuilt` by up to `grown` voxels more (a site that grew by less than half a voxel
/// keeps the value its voxels were computed with).
void expectSameField(const EsdfLayer& incremental, const EsdfLayer& rebuilt, float tolerance,
                     float grown = 0.0f) {
  expectDistancesFollowTheirSites(incremental);
  expectDistancesFollowTheirSites(rebuilt);
  ASSERT_EQ(incremental.numBlocks(), rebuilt.numBlocks());
  int compared = 0;
  for (const auto& [key, block] : rebuilt.blocks()) {
    for (int i = 0; i < rebuilt.voxelsPerBlock(); ++i) {
      const GlobalVoxelIndex global = block->index * 8 + GridIndex(i & 7, (i >> 3) & 7, i >> 6);
      VoxelState s1, s2;
      float d1, d2;
      ASSERT_TRUE(voxelDistance(incremental, global, &s1, &d1));
      ASSERT_TRUE(voxelDistance(rebuilt, global, &s2, &d2));
      ASSERT_EQ(s1, s2);
      ASSERT_LE(d1, d2 + tolerance * kVoxel) << global.transpose();
      ASSERT_GE(d1, d2 - (tolerance + grown) * kVoxel) << global.transpose();
      ++compared;
    }
  }
  EXPECT_GT(compared, 0);
}

/// A wall and a ball that moves: the ball's voxels change state both ways. Constructed with
/// the field of `before` computed; moveBall() writes `after` into the TSDF.
struct MovingBall {
  MovingBall() {
    esdf_test::writeTsdf(&tsdf, before, lo, hi, kTruncation);
    integrator.update(tsdf, &esdf);
  }
  void moveBall() { esdf_test::writeTsdf(&tsdf, after, lo, hi, kTruncation); }

  Sdf before =
      esdf_test::unite(esdf_test::planeX(-0.6f), esdf_test::ball({0.2f, 0.1f, 0.0f}, 0.25f));
  Sdf after =
      esdf_test::unite(esdf_test::planeX(-0.6f), esdf_test::ball({0.55f, -0.1f, 0.05f}, 0.2f));
  Eigen::Vector3f lo{-0.8f, -0.8f, -0.8f}, hi{1.2f, 0.8f, 0.8f};
  TsdfLayer tsdf{geometry()};
  EsdfLayer esdf{geometry(), 1.0f};
  EsdfIntegrator integrator{fieldConfig()};
};

TEST(EsdfIntegratorTest, AMovedObstacleRaisesAndLowersLikeARebuild) {
  MovingBall scene;
  const Sdf& after = scene.after;
  TsdfLayer& tsdf = scene.tsdf;
  EsdfLayer& esdf = scene.esdf;
  EsdfIntegrator& integrator = scene.integrator;

  scene.moveBall();
  const EsdfUpdateStats stats = integrator.update(tsdf, &esdf);
  EXPECT_FALSE(stats.rebuilt);
  EXPECT_GT(stats.sites_removed, 0u);
  EXPECT_GT(stats.sites_added, 0u);
  EXPECT_LT(stats.tsdf_blocks_read, tsdf.numBlocks());  // the wall's far blocks did not change

  EsdfLayer rebuilt(geometry(), 1.0f);
  EsdfIntegrator(fieldConfig()).rebuild(tsdf, &rebuilt);
  // Both carry sites by the same brushfire, reached in different orders: a voxel between two
  // almost equally near sites may take either. The ball's sites that grew by less than half
  // a voxel keep their old value.
  expectSameField(esdf, rebuilt, 0.1f, 0.5f);
  const Errors errors = compare(esdf, after);
  EXPECT_LT(errors.quantile(0.5), 0.1f);
  EXPECT_LT(errors.max(), 0.7f);
}

TEST(EsdfIntegratorTest, ASurfaceMovingAwayHandsItsVoxelsToANearerOne) {
  // A wall at x = 0 and a ball beyond it; the wall then moves 0.6 voxel away. Its surface
  // voxels grow by more than half a voxel (or stop being surface voxels): the voxels between
  // wall and ball that took the wall must go to the ball where it is now nearer, as a
  // rebuild has them. A further move by 0.3 voxel is not taken: the voxels keep answers up
  // to half a voxel below the rebuild's (the safe side), and never above it.
  const Sdf ball = esdf_test::ball({0.6f, 0.0f, 0.0f}, 0.2f);
  const Eigen::Vector3f lo(-0.4f, -0.4f, -0.4f), hi(1.2f, 0.4f, 0.4f);
  TsdfLayer tsdf(geometry());
  esdf_test::writeTsdf(&tsdf, esdf_test::unite(esdf_test::planeX(0.0f), ball), lo, hi, kTruncation);
  EsdfLayer esdf(geometry(), 1.0f);
  EsdfIntegrator integrator(fieldConfig());
  integrator.update(tsdf, &esdf);
  const Sdf after = esdf_test::unite(esdf_test::planeX(-0.6f * kVoxel), ball);
  esdf_test::writeTsdf(&tsdf, after, lo, hi, kTruncation);
  EXPECT_FALSE(integrator.update(tsdf, &esdf).rebuilt);
  EsdfLayer rebuilt(geometry(), 1.0f);
  EsdfIntegrator(fieldConfig()).rebuild(tsdf, &rebuilt);
  expectSameField(esdf, rebuilt, 0.1f);
  EXPECT_LT(compare(esdf, after).max(), 0.7f);

  const Sdf further = esdf_test::unite(esdf_test::planeX(-0.9f * kVoxel), ball);
  esdf_test::writeTsdf(&tsdf, further, lo, hi, kTruncation);
  EXPECT_EQ(integrator.update(tsdf, &esdf).voxels_popped, 0u);  // nothing nearer, no raise
  EsdfLayer rebuilt_further(geometry(), 1.0f);
  EsdfIntegrator(fieldConfig()).rebuild(tsdf, &rebuilt_further);
  expectSameField(esdf, rebuilt_further, 0.1f, 0.5f);
}

TEST(EsdfIntegratorTest, ASnapshotKeepsItsFieldWhileTheLayerIsUpdated) {
  MovingBall scene;
  const Sdf &before = scene.before, &after = scene.after;
  TsdfLayer& tsdf = scene.tsdf;
  EsdfLayer& esdf = scene.esdf;
  EsdfIntegrator& integrator = scene.integrator;
  const std::shared_ptr<const EsdfLayer> snapshot = esdf.snapshot();
  EsdfLayer old_field(geometry(), 1.0f);  // an independent copy of the field before the move
  EsdfIntegrator(fieldConfig()).rebuild(tsdf, &old_field);
  expectSameField(*snapshot, esdf, 0.0f);
  // Records and table only: the voxels are the layer's.
  EXPECT_EQ(snapshot->memoryBytes(),
            esdf.memoryBytes() - esdf.numBlocks() * 512 * sizeof(EsdfVoxel) +
                (snapshot->blocks().capacity() - esdf.blocks().capacity()) *
                    (sizeof(EsdfLayer::BlockMap::value_type) + 1));

  // The obstacle moves and a new slab of blocks arrives: the layer follows, the snapshot
  // still answers the old field everywhere, through its own neighbour links.
  scene.moveBall();
  esdf_test::writeTsdf(&tsdf, after, {1.7f, -0.8f, -0.8f}, {2.1f, 0.8f, 0.8f}, kTruncation);
  const EsdfUpdateStats stats = integrator.update(tsdf, &esdf);
  EXPECT_FALSE(stats.rebuilt);
  EXPECT_GT(stats.esdf_blocks_added, 0u);
  expectSameField(*snapshot, old_field, 0.1f);
  EXPECT_LT(compare(*snapshot, before).max(), 0.7f);
  EXPECT_LT(compare(esdf, after).max(), 0.7f);
  EXPECT_EQ(snapshot->numBlocks(), old_field.numBlocks());
  for (const auto& [key, block] : snapshot->blocks()) {
    for (int slot = 0; slot < 27; ++slot) {
      const EsdfBlock* n = block->neighbours[static_cast<size_t>(slot)];
      if (n != nullptr) {
        EXPECT_EQ(n, snapshot->getBlock(n->index)) << "a link out of the snapshot";
      }
    }
  }
  // A second snapshot sees the update; the first is unchanged by it.
  expectSameField(*esdf.snapshot(), esdf, 0.0f);
  expectSameField(*snapshot, old_field, 0.1f);
}

TEST(EsdfIntegratorTest, AVanishedObstacleLeavesNoDistanceBehind) {
  const Eigen::Vector3f lo(-0.6f, -0.6f, -0.6f), hi(0.6f, 0.6f, 0.6f);
  TsdfLayer tsdf(geometry());
  esdf_test::writeTsdf(&tsdf, esdf_test::ball({0.0f, 0.0f, 0.0f}, 0.2f), lo, hi, kTruncation);
  EsdfLayer esdf(geometry(), 1.0f);
  EsdfIntegrator integrator(fieldConfig());
  integrator.update(tsdf, &esdf);
  esdf_test::writeTsdf(&tsdf, esdf_test::empty(), lo, hi, kTruncation);
  integrator.update(tsdf, &esdf);
  // Every voxel is now observed free with no obstacle anywhere: the cap, exactly.
  for (const auto& [key, block] : esdf.blocks()) {
    for (int i = 0; i < esdf.voxelsPerBlock(); ++i) {
      const EsdfVoxel& v = block->voxel(i);
      ASSERT_EQ(v.state, VoxelState::kFree);
      ASSERT_FALSE(v.hasSite());
      ASSERT_EQ(v.flags, 0);
    }
  }
  EXPECT_EQ(queryNearest(esdf, {0.01f, 0.02f, 0.03f}).distance, 1.0f);
}

/// The field of a wall x < `wall` seen obliquely: the projective TSDF holds `ray_factor`
/// times the distance across the surface, clamped at `truncation`.
void obliqueWallField(float wall, float ray_factor, float truncation, EsdfLayer* esdf) {
  TsdfLayer tsdf(geometry());
  const Sdf across = esdf_test::planeX(wall);
  const Sdf along_ray = [&across, ray_factor](const Eigen::Vector3f& p) {
    return ray_factor * across(p);
  };
  esdf_test::writeTsdf(&tsdf, along_ray, {-0.4f, -0.4f, -0.4f}, {1.59f, 0.39f, 0.39f},
                       truncation);
  EsdfIntegrator(fieldConfig()).update(tsdf, esdf);
}

/// The voxels at (x, 0.025, 0.025) for x in `xs` are free and answer x - wall.
void expectFreeAcross(const EsdfLayer& esdf, float wall, std::initializer_list<float> xs) {
  for (const float x : xs) {
    VoxelState state;
    float distance;
    ASSERT_TRUE(voxelDistance(esdf, esdf.globalVoxelIndexFromPoint({x, 0.025f, 0.025f}), &state,
                              &distance));
    EXPECT_EQ(state, VoxelState::kFree);
    EXPECT_NEAR(distance, x - wall, 1e-5f) << x;
  }
}

TEST(EsdfIntegratorTest, AProjectiveTsdfAnswersTheDistanceAcrossTheSurface) {
  // A wall x < 0.31 seen at 48 degrees from its normal: the projective TSDF holds 1.5 times
  // the distance across the surface (clamped at the truncation).
  EsdfLayer esdf(geometry(), 1.0f);
  obliqueWallField(0.31f, 1.5f, kTruncation, &esdf);
  // The free side answers the distance across the surface, not along the ray: the site at
  // 0.325 (TSDF 0.0225, gradient 1.5), and every voxel farther out through it.
  expectFreeAcross(esdf, 0.31f, {0.325f, 0.375f, 0.525f, 0.975f});
  // The occupied side keeps its TSDF value.
  EXPECT_NEAR(queryNearest(esdf, {0.28f, 0.0f, 0.0f}).distance, 1.5f * (0.275f - 0.31f), 1e-5f);
}

TEST(EsdfIntegratorTest, AVoxelWithinOneVoxelAcrossTheSurfaceIsASiteWhateverItsRayDistance) {
  // A wall x < 0.335 seen at 60 degrees from its normal: the TSDF holds twice the distance
  // across. The voxel at 0.375 lies 0.04 across but 0.08 (over a voxel) along the ray: it is
  // a site answering 0.04, not a voxel reached through the occupied site at 0.325 (which
  // would give 0.05 - 0.02 = 0.03).
  EsdfLayer esdf(geometry(), 1.0f);
  obliqueWallField(0.335f, 2.0f, 0.3f, &esdf);
  expectFreeAcross(esdf, 0.335f, {0.375f, 0.425f, 0.675f});
  const GlobalVoxelIndex at = esdf.globalVoxelIndexFromPoint({0.375f, 0.025f, 0.025f});
  EXPECT_TRUE(esdf.getVoxel(at)->isSite());
  EXPECT_FALSE(esdf.getVoxel(at + GlobalVoxelIndex(1, 0, 0))->isSite());
}

TEST(EsdfIntegratorTest, BlocksArrivingOneByOneGiveTheRebuiltField) {
  const Sdf scene = esdf_test::unite(esdf_test::planeX(-0.5f),
                                     esdf_test::box({0.1f, -0.2f, -0.1f}, {0.3f, 0.35f, 0.2f}));
  for (const int band : {0, 1}) {
    SCOPED_TRACE(band);
    EsdfConfig config = fieldConfig();
    config.band_blocks = band;
    TsdfLayer tsdf(geometry());
    EsdfLayer esdf(geometry(), 1.0f);
    EsdfIntegrator integrator(config);
    // Slabs along x, as a camera moving along the room would add them (with a band, each
    // slab turns the previous one's band blocks into observed ones).
    for (float x = -0.7f; x < 1.1f; x += 0.3f) {
      esdf_test::writeTsdf(&tsdf, scene, {x, -0.5f, -0.5f}, {x + 0.29f, 0.5f, 0.5f},
                           kTruncation);
      const EsdfUpdateStats stats = integrator.update(tsdf, &esdf);
      EXPECT_FALSE(stats.rebuilt);
    }
    EsdfLayer rebuilt(geometry(), 1.0f);
    EsdfIntegrator(config).rebuild(tsdf, &rebuilt);
    expectSameField(esdf, rebuilt, 0.1f);
    EXPECT_LT(compare(esdf, scene).max(), 0.7f);
  }
}

TEST(EsdfIntegratorTest, ABandCarriesTheDistanceToTheObstaclesBesideTheTsdfBlocks) {
  // A ball of radius 0.2 at the origin, observed over blocks -1..0 per axis (0.8 m cube).
  TsdfLayer tsdf(geometry());
  const Sdf ball = esdf_test::ball({0.0f, 0.0f, 0.0f}, 0.2f);
  esdf_test::writeTsdf(&tsdf, ball, {-0.4f, -0.4f, -0.4f}, {0.39f, 0.39f, 0.39f}, kTruncation);
  ASSERT_EQ(tsdf.numBlocks(), 8u);
  EsdfConfig config = fieldConfig();
  config.band_blocks = 1;
  EsdfLayer esdf(geometry(), 1.0f);
  const EsdfUpdateStats stats = EsdfIntegrator(config).update(tsdf, &esdf);
  // Blocks -2..1 per axis: the 8 observed ones and 56 band blocks around them.
  EXPECT_EQ(esdf.numBlocks(), 64u);
  EXPECT_EQ(stats.esdf_blocks_added, 64u);
  EXPECT_EQ(stats.tsdf_blocks_read, 8u);
  size_t band_voxels = 0;
  for (const auto& [key, block] : esdf.blocks()) {
    if (!block->isBand()) continue;
    for (int i = 0; i < esdf.voxelsPerBlock(); ++i) {
      const GlobalVoxelIndex global = block->index * 8 + GridIndex(i & 7, (i >> 3) & 7, i >> 6);
      const Eigen::Vector3f centre = esdf.globalVoxelCenter(global);
      VoxelState state;
      float distance;
      ASSERT_TRUE(voxelDistance(esdf, global, &state, &distance));
      ASSERT_EQ(state, VoxelState::kUnknown);  // no band voxel is observed
      // The distance to the ball, as in observed space: within a fraction of a voxel,
      // never under it, up to the cap.
      const float truth = std::min(ball(centre), 1.0f);
      ASSERT_GE(distance, truth - 0.1f * kVoxel) << centre.transpose();
      ASSERT_LE(distance, truth + 0.5f * kVoxel) << centre.transpose();
      ++band_voxels;
    }
  }
  EXPECT_EQ(band_voxels, 56u * 512u);
  // The band is unknown space: a query there answers unknown, with the ball's distance as
  // its bound.
  const DistanceSample s = queryInterpolated(esdf, {0.6f, 0.0f, 0.0f});
  EXPECT_EQ(s.state, VoxelState::kUnknown);
  EXPECT_TRUE(std::isnan(s.distance));
  EXPECT_NEAR(s.bound, 0.4f, 0.5f * kVoxel);
  // A removed TSDF block rebuilds the field and its band.
  ASSERT_TRUE(tsdf.removeBlock(BlockIndex(0, 0, 0)));
  EsdfIntegrator integrator(config);
  EXPECT_TRUE(integrator.update(tsdf, &esdf).rebuilt);
  // (0, 0, 0) is now a band block; (1, 1, 1) touched only it and is gone.
  EXPECT_EQ(esdf.numBlocks(), 63u);
  EXPECT_EQ(esdf.getBlock(BlockIndex(1, 1, 1)), nullptr);
  ASSERT_NE(esdf.getBlock(BlockIndex(0, 0, 0)), nullptr);
  EXPECT_TRUE(esdf.getBlock(BlockIndex(0, 0, 0))->isBand());
  EXPECT_EQ(queryNearest(esdf, {0.1f, 0.1f, 0.1f}).state, VoxelState::kUnknown);
  EsdfConfig bad = config;
  bad.band_blocks = 3;
  EXPECT_THROW(EsdfIntegrator{bad}, std::invalid_argument);
}

TEST(EsdfIntegratorTest, AnUnchangedLayerIsNotReadAgain) {
  TsdfLayer tsdf(geometry());
  esdf_test::writeTsdf(&tsdf, esdf_test::ball({0.1f, 0.0f, 0.0f}, 0.2f), {-0.4f, -0.4f, -0.4f},
                       {0.4f, 0.4f, 0.4f}, kTruncation);
  EsdfLayer esdf(geometry(), 1.0f);
  EsdfIntegrator integrator(fieldConfig());
  const EsdfUpdateStats first = integrator.update(tsdf, &esdf);
  // The queue's storage at its fullest is counted as the integrator's working memory (with
  // its distance table, under 256 KiB here), and stays counted.
  EXPECT_GT(first.queue_peak_bytes, 0u);
  EXPECT_EQ(EsdfIntegrator(fieldConfig()).workingBytes(), 0u);
  const size_t working = integrator.workingBytes();
  EXPECT_GE(working, first.queue_peak_bytes);
  EXPECT_LE(working, first.queue_peak_bytes + (size_t{1} << 18));
  const EsdfUpdateStats again = integrator.update(tsdf, &esdf);
  EXPECT_EQ(again.tsdf_blocks_read, 0u);
  EXPECT_EQ(again.voxels_popped, 0u);
  EXPECT_LE(again.queue_peak_bytes, size_t{1} << 18);  // only the storage kept between waves
  EXPECT_EQ(integrator.workingBytes(), working);       // constant: a cap sees no wave
  EXPECT_FALSE(again.rebuilt);
  // One block marked changed (as an integrator does) is read again, and only it.
  tsdf.blocks().begin()->second->setUpdated(true);
  EXPECT_EQ(integrator.update(tsdf, &esdf).tsdf_blocks_read, 1u);
}

TEST(EsdfIntegratorTest, ARemovedTsdfBlockRebuildsTheField) {
  TsdfLayer tsdf(geometry());
  const Sdf ball = esdf_test::ball({0.1f, 0.0f, 0.0f}, 0.2f);
  esdf_test::writeTsdf(&tsdf, ball, {-0.4f, -0.4f, -0.4f}, {0.4f, 0.4f, 0.4f}, kTruncation);
  EsdfLayer esdf(geometry(), 1.0f);
  EsdfIntegrator integrator(fieldConfig());
  integrator.update(tsdf, &esdf);
  ASSERT_TRUE(tsdf.removeBlock(BlockIndex(0, 0, 0)));
  const EsdfUpdateStats stats = integrator.update(tsdf, &esdf);
  EXPECT_TRUE(stats.rebuilt);
  EXPECT_EQ(esdf.numBlocks(), tsdf.numBlocks());
  EXPECT_EQ(esdf.getBlock(BlockIndex(0, 0, 0)), nullptr);
  EXPECT_EQ(queryNearest(esdf, {0.1f, 0.1f, 0.1f}).state, VoxelState::kUnknown);
}

TEST(EsdfIntegratorTest, RefusesBadSettingsAndMismatchedLayers) {
  EsdfConfig bad = fieldConfig();
  bad.max_distance_m = 0.0f;
  EXPECT_THROW(EsdfIntegrator{bad}, std::invalid_argument);
  bad = fieldConfig();
  bad.min_weight = std::nanf("");
  EXPECT_THROW(EsdfIntegrator{bad}, std::invalid_argument);
  EXPECT_THROW(EsdfLayer(geometry(), -1.0f), std::invalid_argument);

  TsdfLayer tsdf(geometry());
  EsdfIntegrator integrator(fieldConfig());
  LayerConfig other = geometry();
  other.voxel_size = 0.1f;
  EsdfLayer wrong_geometry(other, 1.0f);
  EXPECT_THROW(integrator.update(tsdf, &wrong_geometry), std::invalid_argument);
  EsdfLayer wrong_cap(geometry(), 2.0f);
  EXPECT_THROW(integrator.update(tsdf, &wrong_cap), std::invalid_argument);
  EsdfIntegrator too_far(fieldConfig(2000.0f));
  EsdfLayer far_layer(geometry(), 2000.0f);
  EXPECT_THROW(too_far.update(tsdf, &far_layer), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
