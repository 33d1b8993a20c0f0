#include "core/integrator/projective_tsdf_integrator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "test/integrator/sphere_views.h"

namespace cblox {
namespace {

using test::kVoxelSize;

// One frame of a tilted plane from a rotated, translated camera, constant weights, no
// drop-off: every observed voxel stores exactly (d - z) ||(x_n, y_n, 1)|| clamped to the
// truncation, with d and (x_n, y_n) the depth and normalised coordinates of the nearest
// pixel; every voxel of the allocated blocks that projects onto a valid pixel within the
// band is observed.
TEST(ProjectiveTsdfIntegrator, OneFrameStoresTheExactProjectiveDistance) {
  TsdfLayer layer(LayerConfig{kVoxelSize, 8});
  IntegratorConfig config;
  config.weight_model = WeightModel::kConstant;
  config.use_weight_dropoff = false;
  ProjectiveTsdfIntegrator integrator(config, &layer);
  const PinholeCamera camera = test::smallCamera();
  const Transformationd T_G_C(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized())),
      Eigen::Vector3d(0.4, -0.3, 0.2));
  const AnalyticScene scene =
      makePlaneScene(Eigen::Vector3d(0, 0, 2.2), Eigen::Vector3d(0.3, 0.1, -1).normalized(), 0.2);
  DepthImage depth(160, 120);
  scene.renderDepth(T_G_C, camera, &depth, nullptr, 10.0);
  const IntegrationStats stats =
      integrator.integrateDepthImage(T_G_C.cast<float>(), depth, camera, nullptr);
  EXPECT_EQ(stats.points_in, 160u * 120u);
  EXPECT_GT(stats.blocks_allocated, 50u);

  const Transformation T_C_G = T_G_C.cast<float>().inverse();
  const float trunc = config.truncation_distance_m;
  size_t observed = 0, expected_observed = 0, skipped_observed = 0;
  for (const auto& [key, block] : layer.blocks()) {
    for (int i = 0; i < block->numVoxels(); ++i) {
      const Eigen::Vector3f p_C = T_C_G * block->voxelCenter(block->localIndex(i));
      const TsdfVoxel& voxel = block->voxel(i);
      const float uf = 150.0f * p_C.x() / p_C.z() + 79.5f + 0.5f;
      const float vf = 150.0f * p_C.y() / p_C.z() + 59.5f + 0.5f;
      // Skip voxels that project within rounding of a pixel border (the integrator steps
      // voxel centres incrementally, so its float rounding may pick the other pixel).
      if (std::abs(uf - std::round(uf)) < 1e-3f || std::abs(vf - std::round(vf)) < 1e-3f) {
        skipped_observed += voxel.observed() ? 1 : 0;
        continue;
      }
      const int u = static_cast<int>(std::floor(uf));
      const int v = static_cast<int>(std::floor(vf));
      const bool in_image = p_C.z() > 0 && u >= 0 && u < 160 && v >= 0 && v < 120;
      if (!in_image || depth(u, v) <= 0.0f) {
        EXPECT_FALSE(voxel.observed());
        continue;
      }
      const float xn = (static_cast<float>(u) - 79.5f) / 150.0f;
      const float yn = (static_cast<float>(v) - 59.5f) / 150.0f;
      const float sdf = (depth(u, v) - p_C.z()) * std::sqrt(1.0f + xn * xn + yn * yn);
      if (sdf < -trunc) {
        EXPECT_FALSE(voxel.observed());
        continue;
      }
      ++expected_observed;
      ASSERT_TRUE(voxel.observed()) << p_C.transpose();
      ++observed;
      EXPECT_NEAR(voxel.distance, std::min(sdf, trunc), 2e-6f);
      EXPECT_FLOAT_EQ(voxel.weight, 1.0f);
    }
  }
  EXPECT_EQ(observed, expected_observed);
  EXPECT_EQ(observed + skipped_observed, stats.voxel_updates);
  EXPECT_LT(skipped_observed, observed / 100);
}

// The block search misses nothing: on a plane at 45 degrees, the voxel containing any
// point near a measured point along its pixel's ray is observed after one frame.
TEST(ProjectiveTsdfIntegrator, BlockSearchCoversTheTruncationBandOfEveryPixel) {
  TsdfLayer layer(LayerConfig{kVoxelSize, 8});
  IntegratorConfig config;
  ProjectiveTsdfIntegrator integrator(config, &layer);
  const PinholeCamera camera = test::smallCamera();
  const AnalyticScene scene =
      makePlaneScene(Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(0, 0.7, -0.7).normalized(), 0.2);
  DepthImage depth(160, 120);
  scene.renderDepth(Transformationd(), camera, &depth, nullptr, 10.0);
  integrator.integrateDepthImage(Transformation(), depth, camera, nullptr);
  size_t checked = 0;
  // Pixels at least 2 px inside the border: a voxel whose centre projects outside the
  // image is never updated, and a block holding only such voxels is not kept.
  for (int v = 2; v < 118; v += 3) {
    for (int u = 2; u < 158; u += 3) {
      if (depth(u, v) <= 0.0f) continue;
      const Eigen::Vector3f ray((u - 79.5f) / 150.0f, (v - 59.5f) / 150.0f, 1.0f);
      // Behind the surface only to -0.3 truncation: a voxel centre can lie 0.87 voxel off
      // the point and project onto a neighbouring pixel ~1 cm deeper.
      for (float s = -0.3f; s <= 0.9f; s += 0.1f) {
        // s > 0: in front of the surface (towards the camera).
        const Eigen::Vector3f p =
            ray * depth(u, v) - ray.normalized() * (s * config.truncation_distance_m);
        const TsdfVoxel* voxel = layer.getVoxelAtPoint(p);
        ASSERT_NE(voxel, nullptr) << "pixel " << u << "," << v << " s " << s;
        ASSERT_TRUE(voxel->observed()) << "pixel " << u << "," << v << " s " << s;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 10000u);
}

// Carving: in front of a wall 2 m away, the space up to the carving depth is mapped as free
// (+truncation, observed); beyond it, up to the band, no block is allocated; without carving
// only the band is.
TEST(ProjectiveTsdfIntegrator, CarvingMapsTheFreeSpaceInFrontOfTheSurfaceUpToItsDepth) {
  const PinholeCamera camera = test::smallCamera();
  const AnalyticScene scene =
      makePlaneScene(Eigen::Vector3d(0, 0, 2.0), Eigen::Vector3d(0, 0, -1), 0.2);
  DepthImage depth(160, 120);
  scene.renderDepth(Transformationd(), camera, &depth, nullptr, 10.0);
  for (const float carving : {0.0f, 1.0f}) {
    TsdfLayer layer(LayerConfig{kVoxelSize, 8});
    IntegratorConfig config;
    config.projective_carving_depth_m = carving;
    ProjectiveTsdfIntegrator integrator(config, &layer);
    integrator.integrateDepthImage(Transformation(), depth, camera, nullptr);
    size_t free = 0;
    for (int v = 4; v < 116; v += 7) {
      for (int u = 4; u < 156; u += 7) {
        const Eigen::Vector3f ray((u - 79.5f) / 150.0f, (v - 59.5f) / 150.0f, 1.0f);
        for (float z = 0.2f; z < 1.95f; z += 0.05f) {
          const TsdfVoxel* voxel = layer.getVoxelAtPoint(ray * z);
          if (carving > 0.0f && z <= carving - 0.02f) {
            // Within the carving depth: free space, every voxel observed at +truncation.
            ASSERT_NE(voxel, nullptr) << u << "," << v << " z " << z;
            ASSERT_TRUE(voxel->observed()) << u << "," << v << " z " << z;
            EXPECT_EQ(voxel->distance, config.truncation_distance_m);
            ++free;
          } else if (z > carving + 0.3f && z < 2.0f - config.truncation_distance_m - 0.3f) {
            // Beyond the blocks' reach from the carved segment and from the band.
            EXPECT_EQ(voxel, nullptr) << u << "," << v << " z " << z;
          }
        }
      }
    }
    EXPECT_EQ(free > 0, carving > 0.0f);
  }
}

TEST(ProjectiveTsdfIntegrator, SphereNearSurfaceVoxelsMatchTheTrueSignedDistance) {
  TsdfLayer layer(LayerConfig{kVoxelSize, 8});
  ProjectiveTsdfIntegrator integrator(IntegratorConfig{}, &layer);
  const PinholeCamera camera = test::smallCamera();
  for (const test::View& view : test::renderSphereViews(8)) {
    integrator.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  }
  const test::DistanceErrors surface = test::surfaceErrors(layer);
  EXPECT_GT(surface.count, 1000u);
  // Measured: RMS 0.14 voxel, max 0.8 voxel (nearest-pixel lookup in 160x120 images).
  EXPECT_LT(surface.rms, 0.2 * kVoxelSize) << "max " << surface.max_abs;
  EXPECT_LT(surface.max_abs, 1.0 * kVoxelSize);
  for (const auto& [key, block] : layer.blocks()) {
    EXPECT_GT(block->countObservedVoxels(), 0) << "empty block left allocated";
  }
  const TsdfVoxel* voxel = layer.getVoxelAtPoint(Eigen::Vector3f(0.5f, 0.0f, 0.0f));
  ASSERT_NE(voxel, nullptr);
  EXPECT_EQ(voxel->color, (Color{200, 60, 20}));
}

// The two layers hold the same blocks with the same voxels, bit for bit.
void expectBitIdenticalLayers(const TsdfLayer& one, const TsdfLayer& two) {
  ASSERT_EQ(one.numBlocks(), two.numBlocks());
  for (const auto& [key, block] : one.blocks()) {
    const Block* other = two.getBlock(block->index());
    ASSERT_NE(other, nullptr);
    for (int i = 0; i < block->numVoxels(); ++i) {
      ASSERT_EQ(block->voxel(i).distance, other->voxel(i).distance);
      ASSERT_EQ(block->voxel(i).weight, other->voxel(i).weight);
      ASSERT_EQ(block->voxel(i).color, other->voxel(i).color);
    }
  }
}

TEST(ProjectiveTsdfIntegrator, ThreadsOneAndTwoAreBitIdentical) {
  TsdfLayer one(LayerConfig{kVoxelSize, 8});
  TsdfLayer two(LayerConfig{kVoxelSize, 8});
  IntegratorConfig config;
  config.num_threads = 1;
  ProjectiveTsdfIntegrator integrator_one(config, &one);
  config.num_threads = 2;
  ProjectiveTsdfIntegrator integrator_two(config, &two);
  const PinholeCamera camera = test::smallCamera();
  for (const test::View& view : test::renderSphereViews(5)) {
    integrator_one.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
    integrator_two.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  }
  expectBitIdenticalLayers(one, two);
}

// The block search keeps the blocks it found in a cube of bits around the sensor; with rays
// so long that the cube would be too large it uses the hash set instead. Both find the same
// blocks: the layers are bit-identical (every depth here is far below either ray limit).
TEST(ProjectiveTsdfIntegrator, BlockCubeAndHashSetSearchesAreBitIdentical) {
  TsdfLayer cube(LayerConfig{kVoxelSize, 8});
  TsdfLayer hash(LayerConfig{kVoxelSize, 8});
  IntegratorConfig config;
  ProjectiveTsdfIntegrator cube_integrator(config, &cube);
  config.max_ray_length_m = 1e4f;  // a cube of (2 * 1.1e4 / 0.16)^3 blocks: too large
  ProjectiveTsdfIntegrator hash_integrator(config, &hash);
  const PinholeCamera camera = test::smallCamera();
  for (const test::View& view : test::renderSphereViews(5)) {
    cube_integrator.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
    hash_integrator.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  }
  EXPECT_GT(cube.numBlocks(), 100u);
  expectBitIdenticalLayers(cube, hash);
}

// A cell whose 64 depths run from 0.4 m to 3 m in steps under the truncation is one segment
// 2.6 m long; with 4 cm blocks and the camera looking along +x its box is about 73 blocks
// wide in x, more than the 64 bits the block cube's search reads at once. The cube's search
// and the hash set's find the same blocks.
TEST(ProjectiveTsdfIntegrator, BlockCubeSearchOfBoxesWiderThan64BlocksMatchesTheHashSet) {
  const LayerConfig layer_config{0.01f, 4};  // 4 cm blocks
  TsdfLayer cube(layer_config);
  TsdfLayer hash(layer_config);
  IntegratorConfig config;
  config.truncation_distance_m = 0.1f;
  config.max_ray_length_m = 4.0f;  // a cube of 231^3 blocks: usable
  ProjectiveTsdfIntegrator cube_integrator(config, &cube);
  config.max_ray_length_m = 100.0f;  // a cube of 5515^3 blocks: the hash set
  ProjectiveTsdfIntegrator hash_integrator(config, &hash);
  const PinholeCamera camera = test::smallCamera();  // ray factors <= 1.2: rays <= 3.6 m
  DepthImage depth(camera.intrinsics().width, camera.intrinsics().height, 0.0f);
  for (int v = 56; v < 64; ++v) {  // one row of 10 cells near the optical axis
    for (int u = 40; u < 120; ++u) {
      depth(u, v) = 0.4f + 2.6f * static_cast<float>((v % 8) * 8 + u % 8) / 63.0f;  // 4.1 cm apart
    }
  }
  Eigen::Matrix3f R_G_C;  // x_C -> -y_G, y_C -> -z_G, z_C (the optical axis) -> +x_G
  R_G_C << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Transformation T_G_C(Eigen::Quaternionf(R_G_C), Eigen::Vector3f(0.13f, -0.07f, 0.02f));
  const IntegrationStats a = cube_integrator.integrateDepthImage(T_G_C, depth, camera, nullptr);
  const IntegrationStats b = hash_integrator.integrateDepthImage(T_G_C, depth, camera, nullptr);
  EXPECT_GT(cube.numBlocks(), 500u);
  EXPECT_EQ(a.voxel_updates, b.voxel_updates);
  expectBitIdenticalLayers(cube, hash);
  // The blocks reach from about 0.4 m to 3 m along x: wider than 64 blocks of 4 cm.
  int x_min = std::numeric_limits<int>::max(), x_max = std::numeric_limits<int>::min();
  for (const BlockIndex& index : cube.blockIndices()) {
    x_min = std::min(x_min, index.x());
    x_max = std::max(x_max, index.x());
  }
  EXPECT_GT(x_max - x_min + 1, 64);
}

TEST(ProjectiveTsdfIntegrator, TimeBudgetCutsTheFrameAndCountsWhatItSkipped) {
  const PinholeCamera camera = test::smallCamera();
  const test::View view = test::renderSphereViews(1).front();
  IntegratorConfig config;
  TsdfLayer full_layer(LayerConfig{kVoxelSize, 8});
  const IntegrationStats full =
      ProjectiveTsdfIntegrator(config, &full_layer)
          .integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  EXPECT_FALSE(full.budget_exhausted);
  EXPECT_EQ(full.blocks_not_reached, 0u);
  ASSERT_GT(full.voxel_updates, 0u);

  // A budget that has run out before the voxel phase: nothing is updated, every block the
  // frame needed is counted as not reached, and no empty block is left in the layer.
  config.max_integration_time_s = 1e-9;
  TsdfLayer cut_layer(LayerConfig{kVoxelSize, 8});
  const IntegrationStats cut =
      ProjectiveTsdfIntegrator(config, &cut_layer)
          .integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  EXPECT_TRUE(cut.budget_exhausted);
  EXPECT_EQ(cut.voxel_updates, 0u);
  EXPECT_GE(cut.blocks_not_reached, full_layer.numBlocks());
  EXPECT_EQ(cut_layer.numBlocks(), 0u);

  // A generous budget changes nothing: bit-identical to the unlimited run.
  config.max_integration_time_s = 60.0;
  TsdfLayer generous_layer(LayerConfig{kVoxelSize, 8});
  const IntegrationStats generous =
      ProjectiveTsdfIntegrator(config, &generous_layer)
          .integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  EXPECT_FALSE(generous.budget_exhausted);
  EXPECT_EQ(generous.voxel_updates, full.voxel_updates);
  expectBitIdenticalLayers(full_layer, generous_layer);
}

// Blocks of 2^3 voxels take the scalar projection path (rows shorter than a SIMD vector),
// 8^3 the SIMD one. After one frame the voxels observed in both volumes agree to float
// rounding (voxel centres are reached by different sums), except the rare voxel whose
// centre projects within rounding of a pixel border and so reads the neighbour pixel.
TEST(ProjectiveTsdfIntegrator, ScalarAndSimdProjectionAgree) {
  TsdfLayer small_blocks(LayerConfig{kVoxelSize, 2});
  TsdfLayer large_blocks(LayerConfig{kVoxelSize, 8});
  ProjectiveTsdfIntegrator scalar(IntegratorConfig{}, &small_blocks);
  ProjectiveTsdfIntegrator simd(IntegratorConfig{}, &large_blocks);
  const PinholeCamera camera = test::smallCamera();
  const test::View view = test::renderSphereViews(1)[0];
  scalar.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  simd.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
  size_t compared = 0, differing = 0;
  for (const auto& [key, block] : small_blocks.blocks()) {
    for (int i = 0; i < block->numVoxels(); ++i) {
      const Eigen::Vector3f centre = block->voxelCenter(block->localIndex(i));
      const TsdfVoxel* other = large_blocks.getVoxelAtPoint(centre);
      if (other == nullptr || !block->voxel(i).observed() || !other->observed()) continue;
      ++compared;
      differing += std::abs(block->voxel(i).distance - other->distance) > 1e-5f ? 1 : 0;
    }
  }
  EXPECT_GT(compared, 5000u);
  EXPECT_LT(differing, compared / 200) << differing << " of " << compared;
}

TEST(ProjectiveTsdfIntegrator, BadDepthsAreSkippedAndCounted) {
  TsdfLayer layer(LayerConfig{kVoxelSize, 8});
  IntegratorConfig config;
  config.max_ray_length_m = 3.0f;
  ProjectiveTsdfIntegrator integrator(config, &layer);
  const PinholeCamera camera = test::smallCamera();
  DepthImage depth(160, 120, 1.0f);
  depth(0, 0) = std::numeric_limits<float>::quiet_NaN();
  depth(1, 0) = std::numeric_limits<float>::infinity();
  depth(2, 0) = 0.0f;
  depth(3, 0) = -1.0f;
  depth(4, 0) = 3.5f;
  depth(5, 0) = 0.05f;
  const IntegrationStats stats =
      integrator.integrateDepthImage(Transformation(), depth, camera, nullptr);
  EXPECT_EQ(stats.points_invalid, 4u);
  EXPECT_EQ(stats.points_out_of_range, 2u);
  EXPECT_GT(stats.voxel_updates, 0u);
  // Nothing is observed far beyond the valid surface at z = 1.
  const TsdfVoxel* behind = layer.getVoxelAtPoint(Eigen::Vector3f(0.0f, 0.0f, 1.2f));
  EXPECT_TRUE(behind == nullptr || !behind->observed());

  DepthImage wrong_size(80, 60, 1.0f);
  EXPECT_THROW(integrator.integrateDepthImage(Transformation(), wrong_size, camera, nullptr),
               std::invalid_argument);
  ColorImage wrong_color(80, 60);
  EXPECT_THROW(integrator.integrateDepthImage(Transformation(), depth, camera, &wrong_color),
               std::invalid_argument);
  // An all-invalid image changes nothing.
  TsdfLayer empty_layer(LayerConfig{kVoxelSize, 8});
  ProjectiveTsdfIntegrator empty_integrator(config, &empty_layer);
  const IntegrationStats none = empty_integrator.integrateDepthImage(
      Transformation(), DepthImage(160, 120, 0.0f), camera, nullptr);
  EXPECT_EQ(none.points_invalid, 160u * 120u);
  EXPECT_EQ(empty_layer.numBlocks(), 0u);
}

}  // namespace
}  // namespace cblox
