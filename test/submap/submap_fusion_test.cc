#include "core/submap/submap_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "test/submap/submap_test_scene.h"

namespace cblox {
namespace {

constexpr float kVoxel = test::kVoxelSize;

Transformationd pose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  return Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized())), t);
}

SubmapCollectionConfig collectionConfig() {
  SubmapCollectionConfig config;
  config.layer = LayerConfig{kVoxel, 8};
  return config;
}

TsdfVoxel* voxelAt(TsdfLayer* layer, const GlobalVoxelIndex& g) {
  BlockIndex block;
  GridIndex local;
  splitGlobalVoxelIndex(g, layer->voxelsPerSideLog2(), &block, &local);
  return &layer->allocateBlock(block)->voxel(local);
}

TEST(SubmapFusionConfig, ValidateNamesTheField) {
  SubmapFusionConfig config;
  EXPECT_EQ(config.validate(), "");
  config.min_weight = 0.0f;
  EXPECT_NE(config.validate().find("min_weight"), std::string::npos);
  config = SubmapFusionConfig{};
  config.max_weight = std::nanf("");
  EXPECT_NE(config.validate().find("max_weight"), std::string::npos);
  config = SubmapFusionConfig{};
  config.num_threads = 0;
  EXPECT_NE(config.validate().find("num_threads"), std::string::npos);
  TsdfLayer a(LayerConfig{}), b(LayerConfig{});
  EXPECT_THROW(fuseLayers(a, Transformationd(), config, &b), std::invalid_argument);
  EXPECT_THROW(fuseLayers(a, Transformationd(), SubmapFusionConfig{}, &a), std::invalid_argument);
  EXPECT_THROW(fuseLayers(a, Transformationd(), SubmapFusionConfig{}, nullptr),
               std::invalid_argument);
}

// Identical grids (identity relative pose): every target voxel becomes the exact weighted
// average of itself and the source voxel; target voxels without an observed source voxel
// are untouched; unobserved target voxels copy the source; weights cap at max_weight.
TEST(FuseLayers, IdenticalGridsGiveExactWeightedAverages) {
  TsdfLayer source(LayerConfig{kVoxel, 8}), target(LayerConfig{kVoxel, 8});
  *voxelAt(&source, {0, 0, 0}) = TsdfVoxel{0.01f, 2.0f, Color{200, 0, 0}};
  *voxelAt(&target, {0, 0, 0}) = TsdfVoxel{-0.03f, 3.0f, Color{0, 100, 50}};
  *voxelAt(&source, {7, 3, -1}) = TsdfVoxel{-0.05f, 0.25f, Color{10, 20, 30}};  // target empty
  *voxelAt(&target, {1, 0, 0}) = TsdfVoxel{0.02f, 1.0f, Color{1, 2, 3}};        // source unobserved
  *voxelAt(&source, {2, 0, 0}) = TsdfVoxel{0.04f, 90.0f, Color{0, 0, 0}};
  *voxelAt(&target, {2, 0, 0}) = TsdfVoxel{0.00f, 20.0f, Color{0, 0, 0}};
  *voxelAt(&source, {3, 0, 0}) = TsdfVoxel{0.04f, 5e-5f, Color{0, 0, 0}};  // below min_weight
  *voxelAt(&target, {3, 0, 0}) = TsdfVoxel{0.01f, 1.0f, Color{0, 0, 0}};

  SubmapFusionConfig config;
  config.max_weight = 100.0f;
  const SubmapFusionStats stats = fuseLayers(source, Transformationd(), config, &target);
  EXPECT_EQ(stats.voxels_fused, 3u);
  EXPECT_EQ(stats.source_blocks, 2u);  // blocks (0,0,0) and (0,0,-1)

  const TsdfVoxel& a = *target.getVoxel({0, 0, 0});
  EXPECT_EQ(a.distance, (-0.03f * 3.0f + 0.01f * 2.0f) / 5.0f);
  EXPECT_EQ(a.weight, 5.0f);
  EXPECT_EQ(a.color, (Color{80, 60, 30}));  // (200*2 + 0*3)/5, (100*3)/5, (50*3)/5
  const TsdfVoxel& copied = *target.getVoxel({7, 3, -1});
  EXPECT_EQ(copied.distance, -0.05f);
  EXPECT_EQ(copied.weight, 0.25f);
  EXPECT_EQ(copied.color, (Color{10, 20, 30}));
  const TsdfVoxel& untouched = *target.getVoxel({1, 0, 0});
  EXPECT_EQ(untouched.distance, 0.02f);
  EXPECT_EQ(untouched.weight, 1.0f);
  EXPECT_EQ(untouched.color, (Color{1, 2, 3}));
  const TsdfVoxel& capped = *target.getVoxel({2, 0, 0});
  EXPECT_EQ(capped.distance, (0.0f * 20.0f + 0.04f * 90.0f) / 110.0f);
  EXPECT_EQ(capped.weight, 100.0f);
  EXPECT_EQ(target.getVoxel({3, 0, 0})->distance, 0.01f);  // source voxel ignored
  EXPECT_TRUE(target.getBlock(BlockIndex(0, 0, -1))->updated());

  // use_color = false leaves target colours as they are.
  TsdfLayer target2(LayerConfig{kVoxel, 8});
  *voxelAt(&target2, {0, 0, 0}) = TsdfVoxel{-0.03f, 3.0f, Color{0, 100, 50}};
  config.use_color = false;
  fuseLayers(source, Transformationd(), config, &target2);
  EXPECT_EQ(target2.getVoxel({0, 0, 0})->color, (Color{0, 100, 50}));
}

// A translation by whole voxels (computed from the float voxel size) shifts voxels exactly,
// with a different target block size too.
TEST(FuseLayers, WholeVoxelTranslationCopiesVoxelsExactly) {
  TsdfLayer source(LayerConfig{kVoxel, 8}), target(LayerConfig{kVoxel, 16});
  for (int i = -9; i < 9; ++i) {
    *voxelAt(&source, {i, 2 * i, -i}) = TsdfVoxel{0.001f * static_cast<float>(i), 1.5f, {}};
  }
  const double v = static_cast<double>(kVoxel);
  const Transformationd T_T_S(Eigen::Quaterniond::Identity(), Eigen::Vector3d(3 * v, -5 * v, 0));
  const SubmapFusionStats stats = fuseLayers(source, T_T_S, SubmapFusionConfig{}, &target);
  EXPECT_EQ(stats.voxels_fused, 18u);
  for (int i = -9; i < 9; ++i) {
    const TsdfVoxel* voxel = target.getVoxel({i + 3, 2 * i - 5, -i});
    ASSERT_NE(voxel, nullptr);
    EXPECT_EQ(voxel->distance, 0.001f * static_cast<float>(i));
    EXPECT_EQ(voxel->weight, 1.5f);
  }
}

// A finite pose that puts the source beyond the blocks the target's grid can index (a hostile
// keyframe pose from the bus): nothing is fused and nothing allocated; a pose that puts it
// partly off the grid fuses the part on it. Found by fuzz_mapper_lcm (the int cast overflowed).
TEST(FuseLayers, SourceBeyondTheGridIsSkipped) {
  TsdfLayer source(LayerConfig{kVoxel, 8});
  for (int i = 0; i < 8; ++i) *voxelAt(&source, {i, 0, 0}) = TsdfVoxel{0.0f, 1.0f, {}};
  for (const double far : {1e12, -1e12, 1e300, -1e300}) {
    TsdfLayer target(LayerConfig{kVoxel, 8});
    const Transformationd T_T_S(Eigen::Quaterniond::Identity(), Eigen::Vector3d(far, 0.0, 0.0));
    EXPECT_EQ(fuseLayers(source, T_T_S, SubmapFusionConfig{}, &target).voxels_fused, 0u) << far;
    EXPECT_EQ(target.numBlocks(), 0u) << far;
  }
  // The grid's last block along x holds voxels (kGridIndexMax + 1) * 8 - 8 ... - 1: the source
  // row i = 0..7 moved to start 4 voxels before the end keeps its first 4 voxels.
  TsdfLayer target(LayerConfig{kVoxel, 8});
  const double v = static_cast<double>(kVoxel);
  const double start = (static_cast<double>(kGridIndexMax) + 1.0) * 8.0 - 4.0;
  const Transformationd T_T_S(Eigen::Quaterniond::Identity(), Eigen::Vector3d(start * v, 0, 0));
  EXPECT_EQ(fuseLayers(source, T_T_S, SubmapFusionConfig{}, &target).voxels_fused, 4u);
}

// Trilinear interpolation reproduces a linear field exactly: with every source voxel
// observed, each covered target voxel gets the field's value at its centre mapped into the
// source (float rounding only), under an arbitrary rotation and translation. Target
// voxels outside the covered region are untouched, and no empty block is left behind.
TEST(FuseLayers, ArbitraryPoseSamplesTheTrilinearValue) {
  TsdfLayer source(LayerConfig{kVoxel, 8}), target(LayerConfig{kVoxel, 8});
  const auto field = [](const Eigen::Vector3d& p) {
    return 0.3 * p.x() - 0.2 * p.y() + 0.1 * p.z() + 0.01;
  };
  for (int z = -1; z <= 0; ++z) {
    for (int y = -1; y <= 1; ++y) {
      for (int x = -1; x <= 0; ++x) {
        Block* block = source.allocateBlock(BlockIndex(x, y, z));
        for (int i = 0; i < block->numVoxels(); ++i) {
          TsdfVoxel& voxel = block->voxel(i);
          voxel.distance =
              static_cast<float>(field(block->voxelCenter(block->localIndex(i)).cast<double>()));
          voxel.weight = 2.0f;
        }
      }
    }
  }
  // A target voxel far from the source region.
  *voxelAt(&target, {100, 0, 0}) = TsdfVoxel{0.05f, 1.0f, {}};
  const Transformationd T_T_S = pose(0.7, {1, -2, 0.5}, {0.123, -0.057, 0.311});
  SubmapFusionConfig config;
  config.num_threads = 2;
  config.min_sample_coverage = 1.0f;  // pure trilinear; the rim is checked below
  const SubmapFusionStats stats = fuseLayers(source, T_T_S, config, &target);
  EXPECT_EQ(stats.source_blocks, 12u);
  EXPECT_GT(stats.voxels_fused, 3000u);
  const Transformationd T_S_T = T_T_S.inverse();
  size_t checked = 0;
  double max_error = 0.0;
  for (const auto& [key, block] : target.blocks()) {
    int observed = 0;
    for (int i = 0; i < block->numVoxels(); ++i) {
      const TsdfVoxel& voxel = block->voxel(i);
      if (!voxel.observed()) continue;
      ++observed;
      if (block->index() == BlockIndex(12, 0, 0)) continue;  // the far voxel
      const Eigen::Vector3d p_S = T_S_T * block->voxelCenter(block->localIndex(i)).cast<double>();
      max_error = std::max(max_error, std::abs(voxel.distance - field(p_S)));
      EXPECT_NEAR(voxel.weight, 2.0f, 1e-5f);
      ++checked;
    }
    EXPECT_GT(observed, 0) << "empty block kept";
  }
  EXPECT_EQ(checked, stats.voxels_fused);
  EXPECT_LT(max_error, 2e-6);
  EXPECT_EQ(target.getVoxel({100, 0, 0})->distance, 0.05f);
  EXPECT_EQ(target.getVoxel({100, 0, 0})->weight, 1.0f);

  // The result does not depend on the number of threads.
  TsdfLayer single(LayerConfig{kVoxel, 8});
  *voxelAt(&single, {100, 0, 0}) = TsdfVoxel{0.05f, 1.0f, {}};
  config.num_threads = 1;
  fuseLayers(source, T_T_S, config, &single);
  EXPECT_TRUE(test::sameVoxels(test::layerVoxels(single), test::layerVoxels(target)));
}

// The documented sample of fuseLayers, evaluated for every voxel of `block` the plain way
// (no cell is skipped): q stepped in float from the block's first voxel, the 8 corners with
// their trilinear coefficients, the rim rule. Returns, per voxel, whether it is sampled and
// (distance, weight).
struct ReferenceSample {
  bool ok = false;
  float distance = 0.0f, weight = 0.0f;
  bool complete = false;  // every needed corner observed
};
std::vector<ReferenceSample> referenceSamples(const TsdfLayer& source, const Transformationd& T_T_S,
                                              const SubmapFusionConfig& config, double t,
                                              const BlockIndex& block, int n_t) {
  const double s = source.voxelSize();
  const Transformationd T_S_T = T_T_S.inverse();
  const Eigen::Matrix3d A = T_S_T.rotationMatrix() * (t / s);
  const Eigen::Vector3d c =
      (T_S_T.rotationMatrix() * Eigen::Vector3d::Constant(0.5 * t) + T_S_T.translation()) / s -
      Eigen::Vector3d::Constant(0.5);
  const Eigen::Matrix3f A_f = A.cast<float>();
  const Eigen::Vector3f q0 = (A * (block * n_t).cast<double>() + c).cast<float>();
  std::vector<ReferenceSample> out(static_cast<size_t>(n_t * n_t * n_t));
  for (int z = 0; z < n_t; ++z) {
    for (int y = 0; y < n_t; ++y) {
      for (int x = 0; x < n_t; ++x) {
        const Eigen::Vector3f q = q0 + A_f.col(2) * static_cast<float>(z) +
                                  A_f.col(1) * static_cast<float>(y) +
                                  A_f.col(0) * static_cast<float>(x);
        GlobalVoxelIndex base(static_cast<int>(std::floor(q.x())),
                              static_cast<int>(std::floor(q.y())),
                              static_cast<int>(std::floor(q.z())));
        Eigen::Vector3f f = q - base.cast<float>();
        for (int axis = 0; axis < 3; ++axis) {
          if (f[axis] >= 1.0f) {
            base[axis] += 1;
            f[axis] = 0.0f;
          }
        }
        float sum_d = 0.0f, sum_w = 0.0f, coverage = 0.0f;
        bool complete = true;
        for (int corner = 0; corner < 8; ++corner) {
          const GridIndex o(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
          const float cx = o.x() ? f.x() : 1.0f - f.x();
          const float cy = o.y() ? f.y() : 1.0f - f.y();
          const float cz = o.z() ? f.z() : 1.0f - f.z();
          if (cx == 0.0f || cy == 0.0f || cz == 0.0f) continue;
          const TsdfVoxel* voxel = source.getVoxel(base + o);
          if (voxel == nullptr || !(voxel->weight >= config.min_weight)) {
            complete = false;
            continue;
          }
          const float weight = cx * cy * cz;
          coverage += weight;
          sum_d += weight * voxel->distance;
          sum_w += weight * voxel->weight;
        }
        ReferenceSample& r = out[static_cast<size_t>((z * n_t + y) * n_t + x)];
        if (complete) {
          r = {true, sum_d, sum_w, true};
        } else if (coverage >= config.min_sample_coverage && coverage > 0.0f) {
          r = {true, sum_d / coverage, sum_w, false};
        }
      }
    }
  }
  return out;
}

// Around a sparse source (isolated blocks, some voxels unobserved) under a rotation most of
// the visited target voxels can read no observed source block; fuseLayers skips them in
// cells and must still give every voxel exactly the documented sample: compared voxel by
// voxel with the plain evaluation of every block near the source, for target voxels equal
// to, half, twice and 4 times the source's. Three quarters of the visited voxels are skipped.
TEST(FuseLayers, SkippedCellsChangeNoVoxelAroundASparseSource) {
  for (const double scale : {1.0, 0.5, 2.0, 4.0}) {
    SCOPED_TRACE("target voxel / source voxel = " + std::to_string(scale));
    TsdfLayer source(LayerConfig{kVoxel, 8});
    const std::vector<BlockIndex> isolated = {{0, 0, 0}, {3, -2, 1}, {-4, 5, -3}, {1, 1, 6}};
    uint32_t state = 12345;
    const auto next = [&] {
      state = state * 1664525u + 1013904223u;
      return static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
    };
    for (const BlockIndex& index : isolated) {
      Block* block = source.allocateBlock(index);
      for (int i = 0; i < block->numVoxels(); ++i) {
        const bool observed = next() < 0.8f;
        block->voxel(i) = TsdfVoxel{next() * 0.2f - 0.1f, observed ? 1.0f + next() : 0.0f, {}};
      }
    }
    const double t = kVoxel * scale;
    TsdfLayer target(LayerConfig{static_cast<float>(t), 8});
    const Transformationd T_T_S = pose(0.9, {0.3, -1, 0.4}, {0.37, -0.81, 0.26});
    SubmapFusionConfig config;
    config.use_color = false;
    config.min_sample_coverage = 0.3f;
    const SubmapFusionStats stats = fuseLayers(source, T_T_S, config, &target);
    EXPECT_EQ(stats.source_blocks, isolated.size());
    const size_t visited_voxels = stats.target_blocks_visited * 512;
    EXPECT_LT(stats.voxels_sampled, visited_voxels / 2) << "cells were not skipped";
    std::printf("[ measured ] scale %.1f: %zu of %zu visited voxels sampled\n", scale,
                stats.voxels_sampled, visited_voxels);
    // Every target block near the source, and every voxel of it, as the plain evaluation
    // says: a kept block holds exactly the samples; a block not kept has no complete sample.
    const double block_t = t * 8;
    Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
    Eigen::Vector3i hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
    for (const BlockIndex& index : isolated) {
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d o(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        const Eigen::Vector3d p_S = (index.cast<double>() * 8 - Eigen::Vector3d::Ones() + o * 10) *
                                    static_cast<double>(kVoxel);
        const Eigen::Vector3d b = (T_T_S * p_S) / block_t;
        for (int axis = 0; axis < 3; ++axis) {
          lo[axis] = std::min(lo[axis], static_cast<int>(std::floor(b[axis])) - 1);
          hi[axis] = std::max(hi[axis], static_cast<int>(std::floor(b[axis])) + 1);
        }
      }
    }
    size_t fused = 0, compared = 0, blocks_checked = 0;
    for (int z = lo.z(); z <= hi.z(); ++z) {
      for (int y = lo.y(); y <= hi.y(); ++y) {
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const BlockIndex index(x, y, z);
          const std::vector<ReferenceSample> reference =
              referenceSamples(source, T_T_S, config, t, index, 8);
          const Block* block = target.getBlock(index);
          ++blocks_checked;
          if (block == nullptr) {
            for (const ReferenceSample& r : reference) {
              ASSERT_FALSE(r.complete) << "block " << index.transpose() << " was dropped";
            }
            continue;
          }
          for (int i = 0; i < block->numVoxels(); ++i) {
            const TsdfVoxel& voxel = block->voxel(i);
            const ReferenceSample& r = reference[static_cast<size_t>(i)];
            ASSERT_EQ(voxel.weight > 0.0f, r.ok) << "block " << index.transpose() << " voxel " << i;
            if (!r.ok) continue;
            ++fused;
            EXPECT_FLOAT_EQ(voxel.distance, r.distance);
            EXPECT_FLOAT_EQ(voxel.weight, r.weight);
            ++compared;
          }
        }
      }
    }
    EXPECT_GT(blocks_checked, stats.target_blocks_visited);
    EXPECT_EQ(fused, stats.voxels_fused);
    EXPECT_GT(compared, scale <= 1.0 ? 500u : 10u);
  }
}

// At the rim of the observed region, a sample whose observed corners carry at least
// min_sample_coverage of the trilinear weight is the renormalised average of those corners
// with the weight sum_obs c_o w_o: the voxels that pure trilinear fusion fills are
// unchanged, and every extra voxel has a weight in [2 C_min, 2) and a distance within the
// field's variation over one cell (|grad| * voxel * sqrt(3)) of the true value.
TEST(FuseLayers, RimSamplesAreRenormalisedOverTheObservedCorners) {
  TsdfLayer source(LayerConfig{kVoxel, 8});
  const Eigen::Vector3d gradient(0.3, -0.2, 0.1);
  const auto field = [&](const Eigen::Vector3d& p) { return gradient.dot(p) + 0.01; };
  for (int x = -1; x <= 1; ++x) {
    Block* block = source.allocateBlock(BlockIndex(x, 0, 0));
    for (int i = 0; i < block->numVoxels(); ++i) {
      TsdfVoxel& voxel = block->voxel(i);
      voxel.distance =
          static_cast<float>(field(block->voxelCenter(block->localIndex(i)).cast<double>()));
      voxel.weight = 2.0f;
    }
  }
  const Transformationd T_T_S = pose(0.4, {0.2, 1, -0.3}, {0.051, 0.013, -0.027});
  SubmapFusionConfig pure;
  pure.min_sample_coverage = 1.0f;
  SubmapFusionConfig rim;  // default coverage
  ASSERT_EQ(rim.min_sample_coverage, 0.5f);
  TsdfLayer pure_target(LayerConfig{kVoxel, 8}), rim_target(LayerConfig{kVoxel, 8});
  const SubmapFusionStats pure_stats = fuseLayers(source, T_T_S, pure, &pure_target);
  const SubmapFusionStats rim_stats = fuseLayers(source, T_T_S, rim, &rim_target);
  ASSERT_GT(pure_stats.voxels_fused, 1000u);  // ~23 x 7 x 7 complete cells
  std::printf("[ measured ] pure trilinear %zu voxels, with rim samples %zu\n",
              pure_stats.voxels_fused, rim_stats.voxels_fused);
  EXPECT_GT(rim_stats.voxels_fused, pure_stats.voxels_fused + 300);

  const Transformationd T_S_T = T_T_S.inverse();
  const double bound = gradient.norm() * kVoxel * std::sqrt(3.0);
  size_t extra = 0;
  double max_rim_error = 0.0;
  for (const auto& [key, block] : rim_target.blocks()) {
    for (int i = 0; i < block->numVoxels(); ++i) {
      const TsdfVoxel& voxel = block->voxel(i);
      if (!voxel.observed()) continue;
      const GridIndex local = block->localIndex(i);
      const GlobalVoxelIndex g = block->index() * 8 + local;
      const TsdfVoxel* pure_voxel = pure_target.getVoxel(g);
      if (pure_voxel != nullptr && pure_voxel->observed()) {
        EXPECT_EQ(voxel.distance, pure_voxel->distance);
        EXPECT_EQ(voxel.weight, pure_voxel->weight);
        continue;
      }
      ++extra;
      EXPECT_GE(voxel.weight, 2.0f * rim.min_sample_coverage - 1e-5f);
      EXPECT_LT(voxel.weight, 2.0f);
      const Eigen::Vector3d p_S = T_S_T * block->voxelCenter(local).cast<double>();
      max_rim_error = std::max(max_rim_error, std::abs(voxel.distance - field(p_S)));
    }
  }
  EXPECT_EQ(extra, rim_stats.voxels_fused - pure_stats.voxels_fused);
  // Rim samples extend blocks that complete samples filled, and never allocate one: the two
  // targets have the same blocks.
  EXPECT_EQ(rim_target.numBlocks(), pure_target.numBlocks());
  for (const auto& [key, block] : rim_target.blocks()) {
    EXPECT_NE(pure_target.getBlock(block->index()), nullptr);
  }
  EXPECT_GT(max_rim_error, 1e-4);  // renormalisation is not trilinear: a real difference
  EXPECT_LT(max_rim_error, bound);
}

struct HalvesScenario {
  std::vector<SyntheticFrame> frames;
  SubmapCollection collection{collectionConfig()};
  std::shared_ptr<Submap> first, second;
};

// First half of an orbit into submap 1 (frame T_G_M1), second half into submap 2, whose
// frame is rotated 20 degrees and shifted 0.37 m so that the grids do not align.
void buildHalves(const Transformationd& T_G_M1, HalvesScenario* s) {
  s->frames = test::renderOrbit(16);
  const size_t half = s->frames.size() / 2;
  const Transformationd T_M1_M2 =
      pose(20.0 * std::numbers::pi / 180.0, {0.3, -0.2, 1}, Eigen::Vector3d(0.37, 0.0, 0.0));
  s->first = s->collection.createSubmap(T_G_M1, 1, 0);
  test::integrateFrames(s->first.get(), s->frames, 0, half);
  s->second = s->collection.createSubmap(T_G_M1 * T_M1_M2, 2, 0);
  s->second->addKeyframe(3);
  test::integrateFrames(s->second.get(), s->frames, half, s->frames.size());
  s->collection.finishActiveSubmap();
}

// Fusing two submaps built from halves of a scene equals integrating it whole, within these
// tolerances: mesh vertex RMSE to the exact scene within 1.5x of the whole integration's and
// below 0.5 voxel; over near-surface voxels (|true distance| < 1 voxel) observed in both,
// |fused - whole| RMS below 0.3 voxel and RMS to the true distance within 1.1x of the whole
// integration's; at least 95% of the whole integration's near-surface voxels observed.
TEST(FuseSubmaps, HalvesEqualTheWholeIntegration) {
  HalvesScenario s;
  const Transformationd T_G_M1 = pose(0.3, {1, 1, 0}, {0.05, -0.11, 0.02});
  buildHalves(T_G_M1, &s);
  TsdfLayer whole(LayerConfig{kVoxel, 8});
  test::integrateFrames(&whole, T_G_M1, s.frames, 0, s.frames.size());

  EXPECT_THROW(fuseSubmaps(*s.second, s.second.get(), SubmapFusionConfig{}), std::invalid_argument);
  const SubmapFusionStats stats = fuseSubmaps(*s.second, s.first.get(), SubmapFusionConfig{});
  // The fused map is hardly larger than the whole integration (1124 blocks against 1067;
  // 1179 when rim samples could allocate blocks).
  std::printf("[ measured ] blocks: fused %zu, whole %zu\n", s.first->layer().numBlocks(),
              whole.numBlocks());
  EXPECT_LE(static_cast<double>(s.first->layer().numBlocks()),
            1.06 * static_cast<double>(whole.numBlocks()));
  EXPECT_GT(stats.voxels_fused, 10000u);
  EXPECT_EQ(s.first->keyframeIds(), (std::vector<KeyframeId>{1, 2, 3}));
  EXPECT_EQ(s.first->numBlocks(), s.first->layer().numBlocks());

  const AnalyticScene scene = makeSphereScene();
  const Transformation T_G_M1f = T_G_M1.cast<float>();
  const Mesh fused_mesh = transformMesh(T_G_M1f, test::meshLayer(s.first->layer()));
  const Mesh whole_mesh = transformMesh(T_G_M1f, test::meshLayer(whole));
  const double fused_rmse = test::vertexRmse(fused_mesh, scene);
  const double whole_rmse = test::vertexRmse(whole_mesh, scene);
  EXPECT_LT(fused_rmse, 1.5 * whole_rmse);
  EXPECT_LT(fused_rmse, 0.5 * kVoxel);

  // Voxel-level comparison near the surface (|true distance| < 1 voxel).
  size_t whole_near = 0, both_near = 0;
  double sq_fused_whole = 0.0, sq_whole_truth = 0.0, sq_fused_truth = 0.0;
  std::vector<double> diffs;
  for (const auto& [key, block] : whole.blocks()) {
    for (int i = 0; i < block->numVoxels(); ++i) {
      const TsdfVoxel& w = block->voxel(i);
      if (!w.observed()) continue;
      const Eigen::Vector3f p_M1 = block->voxelCenter(block->localIndex(i));
      const double truth = scene.signedDistance((T_G_M1f * p_M1).cast<double>());
      if (std::abs(truth) >= kVoxel) continue;
      ++whole_near;
      const TsdfVoxel* f = s.first->layer().getVoxelAtPoint(p_M1);
      if (f == nullptr || !f->observed()) continue;
      ++both_near;
      const double diff = static_cast<double>(f->distance) - w.distance;
      diffs.push_back(std::abs(diff));
      sq_fused_whole += diff * diff;
      sq_whole_truth += (w.distance - truth) * (w.distance - truth);
      sq_fused_truth += (f->distance - truth) * (f->distance - truth);
    }
  }
  ASSERT_GT(both_near, 10000u);
  const double n = static_cast<double>(both_near);
  const double rms_fused_whole = std::sqrt(sq_fused_whole / n);
  const double rms_whole_truth = std::sqrt(sq_whole_truth / n);
  const double rms_fused_truth = std::sqrt(sq_fused_truth / n);
  std::sort(diffs.begin(), diffs.end());
  const double p50 = diffs[diffs.size() / 2], p99 = diffs[diffs.size() * 99 / 100];
  // Resampling the second half (trilinear) changes voxel values by a fraction of a voxel
  // where the projective TSDF is not smooth (grazing views of the ground, the sphere-ground
  // contact); it does not make them less accurate.
  EXPECT_LT(rms_fused_whole, 0.3 * kVoxel);
  EXPECT_LT(rms_fused_truth, 1.1 * rms_whole_truth);
  // Trilinear sampling needs 8 observed neighbours: each half loses the one-voxel rim of its
  // observed region where the other half does not cover it.
  EXPECT_GE(n, 0.95 * static_cast<double>(whole_near));
  std::printf(
      "[ measured ] vertex RMSE to the scene: fused %.5f m (%zu vertices), whole %.5f m (%zu), "
      "ratio %.3f\n[ measured ] near-surface voxels observed in both %zu of %zu (%.2f%%); "
      "|fused - whole| RMS %.5f m, median %.5f m, p99 %.5f m, max %.5f m; RMS to the true "
      "distance: fused %.5f m, whole %.5f m\n[ measured ] fusion %.1f ms, %zu voxels\n",
      fused_rmse, fused_mesh.numVertices(), whole_rmse, whole_mesh.numVertices(),
      fused_rmse / whole_rmse, both_near, whole_near, 100.0 * n / static_cast<double>(whole_near),
      rms_fused_whole, p50, p99, diffs.back(), rms_fused_truth, rms_whole_truth,
      stats.seconds * 1e3, stats.voxels_fused);
}

// projectCollection of two submaps is their fusion: with submap 1's frame at the origin the
// projection's grid is submap 1's, and the result equals fuseSubmaps(2 -> 1) voxel for voxel
// (every observed voxel counts: min_weight = smallest normal float).
double meshArea(const Mesh& mesh) {
  double area = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

// Exporting one subvolume whose grid does not align with G's keeps its surface: with rim
// samples (default min_sample_coverage) the projection's mesh has at least 95 % of the
// subvolume's own mesh area (measured 97.3 %); pure trilinear sampling loses the one-voxel
// rim of the observed region (measured 78.7 %).
TEST(ProjectCollection, OneSubmapKeepsItsSurface) {
  HalvesScenario s;
  buildHalves(Transformationd(), &s);
  MeshIntegrator own_mesher(s.second->layer(), MeshConfig{});
  own_mesher.update(/*only_updated_blocks=*/false);
  const double own_area = meshArea(own_mesher.extractMesh(/*connected=*/true));
  ASSERT_GT(own_area, 1.0);
  s.collection.removeSubmap(s.first->id());
  SubmapFusionConfig rim;
  SubmapFusionConfig pure;
  pure.min_sample_coverage = 1.0f;
  const double rim_area =
      meshArea(meshCollection(s.collection, LayerConfig{kVoxel, 8}, rim, MeshConfig{}, true));
  const double pure_area =
      meshArea(meshCollection(s.collection, LayerConfig{kVoxel, 8}, pure, MeshConfig{}, true));
  std::printf(
      "[ measured ] mesh area: subvolume %.3f m^2, projected %.3f m^2 (%.1f %%), "
      "pure trilinear %.3f m^2 (%.1f %%)\n",
      own_area, rim_area, 100.0 * rim_area / own_area, pure_area, 100.0 * pure_area / own_area);
  EXPECT_GT(rim_area, 0.95 * own_area);
  EXPECT_LT(rim_area, 1.03 * own_area);
  EXPECT_LT(pure_area, rim_area);
}

TEST(ProjectCollection, TwoSubmapsEqualTheirFusion) {
  HalvesScenario s;
  buildHalves(Transformationd(), &s);
  SubmapFusionConfig config;
  config.min_weight = std::numeric_limits<float>::min();
  SubmapFusionStats projection_stats;
  const TsdfLayer projected =
      projectCollection(s.collection, LayerConfig{kVoxel, 8}, config, true, &projection_stats);
  fuseSubmaps(*s.second, s.first.get(), config);

  size_t compared = 0, mismatched = 0;
  double max_diff = 0.0;
  for (const auto& [key, block] : s.first->layer().blocks()) {
    for (int i = 0; i < block->numVoxels(); ++i) {
      const TsdfVoxel& f = block->voxel(i);
      const TsdfVoxel* p = projected.getVoxelAtPoint(block->voxelCenter(block->localIndex(i)));
      const bool p_observed = p != nullptr && p->observed();
      if (f.observed() != p_observed) {
        ++mismatched;
        continue;
      }
      if (!p_observed) continue;
      ++compared;
      max_diff = std::max(max_diff, static_cast<double>(std::abs(f.distance - p->distance)));
      EXPECT_NEAR(f.weight, p->weight, 1e-5f * f.weight);
    }
  }
  size_t projected_observed = 0;
  for (const auto& [key, block] : projected.blocks()) {
    projected_observed += static_cast<size_t>(block->countObservedVoxels());
  }
  EXPECT_GT(compared, 50000u);
  EXPECT_EQ(mismatched, 0u);
  EXPECT_EQ(projected_observed, compared);
  EXPECT_LT(max_diff, 1e-6);
  std::printf("[ measured ] %zu voxels compared, max |projected - fused| %.3g m\n", compared,
              max_diff);

  // The collection's mesh is the mesh of the projection.
  const Mesh mesh =
      meshCollection(s.collection, LayerConfig{kVoxel, 8}, config, MeshConfig{}, true);
  EXPECT_GT(mesh.numVertices(), 1000u);
}

TEST(ProjectCollection, EmptyCollectionGivesAnEmptyLayer) {
  SubmapCollection collection(collectionConfig());
  const TsdfLayer layer = projectCollection(collection, LayerConfig{}, SubmapFusionConfig{});
  EXPECT_EQ(layer.numBlocks(), 0u);
  EXPECT_TRUE(
      meshCollection(collection, LayerConfig{}, SubmapFusionConfig{}, MeshConfig{}).empty());
  // An active submap is left out unless include_active.
  const auto active = collection.createSubmap(Transformationd(), 1, 0);
  *voxelAt(active->mutableLayer(), {0, 0, 0}) = TsdfVoxel{0.01f, 1.0f, {}};
  EXPECT_EQ(projectCollection(collection, LayerConfig{}, SubmapFusionConfig{}, false).numBlocks(),
            0u);
  EXPECT_EQ(projectCollection(collection, LayerConfig{}, SubmapFusionConfig{}, true).numBlocks(),
            1u);
  EXPECT_THROW(fuseSubmaps(*active, collection.createSubmap(Transformationd(), 2, 0).get(),
                           SubmapFusionConfig{}),
               std::invalid_argument);  // the new target is active
}

}  // namespace
}  // namespace cblox
