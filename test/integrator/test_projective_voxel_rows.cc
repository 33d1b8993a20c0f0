#include "core/integrator/projective_voxel_rows.h"

#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/geometry/cpu_features.h"
#include "core/integrator/projective_tsdf_integrator.h"
#include "test/integrator/sphere_views.h"

namespace cblox {
namespace {

using test::kVoxelSize;

// Raw bytes, so the padding byte and the sign of zero count too.
bool sameBytes(const TsdfVoxel& a, const TsdfVoxel& b) {
  return std::memcmp(&a, &b, sizeof(TsdfVoxel)) == 0;
}

// A colour per pixel that differs in every channel (the last pixel included).
void paintPattern(ColorImage* color) {
  for (int v = 0; v < color->height; ++v) {
    for (int u = 0; u < color->width; ++u) {
      (*color)(u, v) = Color{static_cast<uint8_t>(7 * u + v), static_cast<uint8_t>(3 * v + 11),
                             static_cast<uint8_t>(u * v + 5)};
    }
  }
}

// Random voxel rows against random frames: the AVX2 rows give the portable loop's bytes
// and update count, for every rule setting, with and without colours, on rows of 8, 16
// and 64 voxels whose centres fall inside, outside and behind the image, on pixels with
// and without depth (the last pixel included).
TEST(ProjectiveVoxelRows, Avx2RowsMatchThePortableLoopBitForBit) {
  if (!cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2";
  constexpr int kWidth = 40, kHeight = 30;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<ProjectivePixelSample> samples(kWidth * kHeight);
  std::vector<Color> colors(kWidth * kHeight);
  for (size_t p = 0; p < samples.size(); ++p) {
    // A quarter of the pixels without depth; the others on a bumpy surface near 1 m.
    samples[p] = {unit(rng) < 0.25f ? 0.0f : 0.9f + 0.2f * unit(rng), 1.0f + 0.3f * unit(rng)};
    colors[p] = Color{static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng()),
                      static_cast<uint8_t>(rng())};
  }
  samples.back().depth = 1.0f;  // the last pixel is seen (its colour has no bytes after it)
  ProjectiveVoxelRows::Frame frame;
  frame.fx = frame.fy = 30.0f;
  frame.cx = 19.5f;
  frame.cy = 14.5f;
  frame.width = kWidth;
  frame.height = kHeight;
  frame.samples = samples.data();
  size_t compared_updates = 0;
  for (const bool with_colors : {true, false}) {
    frame.colors = with_colors ? colors.data() : nullptr;
    for (const WeightModel model : {WeightModel::kInverseSquare, WeightModel::kConstant}) {
      for (const bool dropoff : {true, false}) {
        for (const ColorBlending blending :
             {ColorBlending::kWeightedAverage, ColorBlending::kOverwrite, ColorBlending::kNone}) {
          IntegratorConfig config;
          config.weight_model = model;
          config.use_weight_dropoff = dropoff;
          config.color_blending = blending;
          config.max_weight = 3.0f;  // reached: the clamp of the weight runs too
          const TsdfVoxelUpdater updater(config, kVoxelSize);
          const ProjectiveVoxelRows portable(frame, updater, false);
          const ProjectiveVoxelRows avx2(frame, updater, true);
          ASSERT_TRUE(avx2.vectorized());
          ASSERT_FALSE(portable.vectorized());
          for (int trial = 0; trial < 300; ++trial) {
            const int count = trial % 3 == 0 ? 8 : trial % 3 == 1 ? 16 : 64;
            std::vector<TsdfVoxel> a(static_cast<size_t>(count));
            for (TsdfVoxel& v : a) {
              v.distance = (unit(rng) - 0.5f) * 0.2f;
              v.weight = unit(rng) < 0.3f ? 0.0f : 3.0f * unit(rng);
              v.color = Color{static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng()),
                              static_cast<uint8_t>(rng())};
              v.padding = static_cast<uint8_t>(rng());
            }
            std::vector<TsdfVoxel> b = a;
            // Rows across the truncation band, some leaving the image or the camera's front.
            const Eigen::Vector3f p0((unit(rng) - 0.5f) * 1.6f, (unit(rng) - 0.5f) * 1.2f,
                                     trial % 10 == 0 ? -0.05f : 0.85f + 0.3f * unit(rng));
            const Eigen::Vector3f step =
                Eigen::Vector3f(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f) *
                (trial % 2 ? 0.02f : 0.005f);
            const size_t n_portable = portable.update(p0, step, count, a.data());
            const size_t n_avx2 = avx2.update(p0, step, count, b.data());
            ASSERT_EQ(n_portable, n_avx2) << "trial " << trial;
            compared_updates += n_portable;
            for (int i = 0; i < count; ++i) {
              ASSERT_TRUE(sameBytes(a[static_cast<size_t>(i)], b[static_cast<size_t>(i)]))
                  << "trial " << trial << " voxel " << i << ": " << a[i].distance << " "
                  << b[i].distance << " " << a[i].weight << " " << b[i].weight << " " << a[i].color
                  << " " << b[i].color;
            }
          }
        }
      }
    }
  }
  EXPECT_GT(compared_updates, 20000u);
}

// The last pixel's colour is blended (gathered one by one: a 4-byte read would pass the
// image's end).
TEST(ProjectiveVoxelRows, TheLastPixelsColourIsBlended) {
  if (!cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2";
  std::vector<ProjectivePixelSample> samples(4 * 4, ProjectivePixelSample{1.0f, 1.0f});
  std::vector<Color> colors(samples.size(), Color{0, 0, 0});
  colors.back() = Color{255, 128, 1};
  ProjectiveVoxelRows::Frame frame;
  frame.fx = frame.fy = 1.0f;
  frame.cx = frame.cy = 1.5f;
  frame.width = frame.height = 4;
  frame.samples = samples.data();
  frame.colors = colors.data();
  IntegratorConfig config;
  config.color_blending = ColorBlending::kOverwrite;
  const ProjectiveVoxelRows rows(frame, TsdfVoxelUpdater(config, kVoxelSize), true);
  // Eight centres at z = 1 m all projecting onto pixel (3, 3), the last one.
  std::vector<TsdfVoxel> row(8);
  EXPECT_EQ(rows.update(Eigen::Vector3f(1.8f, 1.8f, 1.0f), Eigen::Vector3f(0.01f, 0.0f, 0.0f), 8,
                        row.data()),
            8u);
  for (const TsdfVoxel& v : row) EXPECT_EQ(v.color, (Color{255, 128, 1}));
}

// Whole frames of the sphere and of a wall filling the image: the integrator with
// vectorized rows builds the same layer, byte for byte, as without, for 8^3 and 16^3 blocks.
TEST(ProjectiveVoxelRows, IntegratorLayersAreIdenticalWithAndWithoutAvx2) {
  if (!cpuHasAvx2()) GTEST_SKIP() << "this CPU has no AVX2";
  const PinholeCamera camera = test::smallCamera();
  std::vector<test::View> views = test::renderSphereViews(6);
  for (test::View& view : views) paintPattern(&view.color);
  test::View wall{Transformationd(), DepthImage(160, 120, 1.2f), ColorImage(160, 120)};
  paintPattern(&wall.color);
  views.push_back(std::move(wall));
  for (const int vps : {8, 16}) {
    TsdfLayer portable_layer(LayerConfig{kVoxelSize, vps});
    TsdfLayer avx2_layer(LayerConfig{kVoxelSize, vps});
    IntegratorConfig config;
    config.max_weight = 20.0f;
    config.vectorized = false;
    ProjectiveTsdfIntegrator portable(config, &portable_layer);
    config.vectorized = true;
    ProjectiveTsdfIntegrator avx2(config, &avx2_layer);
    for (int pass = 0; pass < 2; ++pass) {
      for (const test::View& view : views) {
        const IntegrationStats a =
            portable.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
        const IntegrationStats b =
            avx2.integrateDepthImage(view.T_G_C.cast<float>(), view.depth, camera, &view.color);
        ASSERT_EQ(a.voxel_updates, b.voxel_updates);
      }
    }
    ASSERT_EQ(portable_layer.numBlocks(), avx2_layer.numBlocks());
    size_t observed = 0;
    for (const auto& [key, block] : portable_layer.blocks()) {
      const Block* other = avx2_layer.getBlock(block->index());
      ASSERT_NE(other, nullptr);
      for (int i = 0; i < block->numVoxels(); ++i) {
        ASSERT_TRUE(sameBytes(block->voxel(i), other->voxel(i))) << "vps " << vps;
        observed += block->voxel(i).observed() ? 1 : 0;
      }
    }
    EXPECT_GT(observed, 20000u) << "vps " << vps;
  }
}

}  // namespace
}  // namespace cblox
