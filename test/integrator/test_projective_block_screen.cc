#include "core/integrator/projective_block_screen.h"

#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/geometry/se3.h"
#include "core/integrator/projective_voxel_rows.h"

namespace cblox {
namespace {

// Random frames and random blocks around their surfaces: the rows of a quadrant the screen
// rejects get no update from the projective voxel loop (portable rows, the same rule as the
// integrator), under every pose; the screen rejects a good share of the blocks whole, parts
// of others, and passes quadrants that are updated.
TEST(ProjectiveBlockScreen, ARejectedQuadrantIsNeverUpdated) {
  constexpr int kWidth = 64, kHeight = 48, kCell = 8, kVps = 8;
  constexpr float kVoxel = 0.05f, kTruncation = 0.2f;
  const float block_size = kVoxel * kVps;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  IntegratorConfig config;
  config.truncation_distance_m = kTruncation;
  const TsdfVoxelUpdater updater(config, kVoxel);
  size_t rejected = 0, partly_rejected = 0, rejected_quadrants = 0;
  size_t passed_and_updated_quadrants = 0;
  for (int frame_index = 0; frame_index < 40; ++frame_index) {
    // A bumpy surface 1.5-3 m away with holes, and the ray factors of a pinhole camera.
    std::vector<ProjectivePixelSample> samples(kWidth * kHeight);
    const float fx = 50.0f, fy = 50.0f, cx = 31.5f, cy = 23.5f;
    const float base = 1.5f + 1.5f * unit(rng);
    for (int v = 0; v < kHeight; ++v) {
      for (int u = 0; u < kWidth; ++u) {
        const float xn = (u - cx) / fx, yn = (v - cy) / fy;
        const bool hole = unit(rng) < 0.1f || (u > 40 && v < 12);  // also an empty region
        samples[v * kWidth + u] = {
            hole ? 0.0f : base + 0.3f * std::sin(0.2f * u) + 0.05f * unit(rng),
            std::sqrt(1.0f + xn * xn + yn * yn)};
      }
    }
    const int cells_x = kWidth / kCell, cells_y = kHeight / kCell;
    std::vector<float> cell_max(cells_x * cells_y, 0.0f);
    for (int v = 0; v < kHeight; ++v) {
      for (int u = 0; u < kWidth; ++u) {
        float& m = cell_max[(v / kCell) * cells_x + u / kCell];
        m = std::max(m, samples[v * kWidth + u].depth);
      }
    }
    // A random camera pose; blocks around the points the camera sees.
    const Eigen::Quaternionf q = Eigen::Quaternionf::UnitRandom();
    const Transformation T_G_C(q, Eigen::Vector3f(unit(rng), unit(rng), unit(rng)) * 2.0f);
    const Transformation T_C_G = T_G_C.inverse();
    RectangleMaxTable cell_table;
    std::copy(cell_max.begin(), cell_max.end(), cell_table.resetGrid(cells_x, cells_y, 2));
    cell_table.buildLevels();
    const ProjectiveBlockScreen screen({T_C_G.rotationMatrix(), T_C_G.translation(), fx, fy,
                                        cx + 0.5f, cy + 0.5f, kWidth, kHeight, kVoxel, kVps,
                                        kTruncation, &cell_table, kCell});
    const ProjectiveVoxelRows rows({fx, fy, cx, cy, kWidth, kHeight, samples.data(), nullptr},
                                   updater, /*vectorized=*/false);
    for (int b = 0; b < 400; ++b) {
      // A point on a random pixel's ray at 0.5-4 m, and the block holding it.
      const Eigen::Vector3f ray((unit(rng) * kWidth - cx) / fx, (unit(rng) * kHeight - cy) / fy,
                                1.0f);
      const Eigen::Vector3f p_G = T_G_C * Eigen::Vector3f(ray * (0.5f + 3.5f * unit(rng)));
      const Eigen::Vector3f origin = (p_G / block_size).array().floor().matrix() * block_size;
      std::vector<TsdfVoxel> voxels(kVps * kVps * kVps);
      const unsigned kept = screen.rowQuadrants(origin);
      // Each quadrant's rows: a rejected one gets no update.
      for (int quadrant = 0; quadrant < 4; ++quadrant) {
        const int y_half = quadrant & 1, z_half = quadrant >> 1;
        std::vector<Eigen::Vector3f> origins;
        size_t updates = 0;
        for (int k = ProjectiveBlockScreen::halfBegin(kVps, z_half);
             k < ProjectiveBlockScreen::halfEnd(kVps, z_half); ++k) {
          for (int j = ProjectiveBlockScreen::halfBegin(kVps, y_half);
               j < ProjectiveBlockScreen::halfEnd(kVps, y_half); ++j) {
            const Eigen::Vector3f p0 =
                T_C_G *
                Eigen::Vector3f(origin + Eigen::Vector3f(0.5f, j + 0.5f, k + 0.5f) * kVoxel);
            updates += rows.update(p0, T_C_G.rotationMatrix().col(0) * kVoxel, kVps,
                                   &voxels[static_cast<size_t>((k * kVps + j) * kVps)]);
          }
        }
        if (!(kept & (1u << quadrant))) {
          ++rejected_quadrants;
          ASSERT_EQ(updates, 0u) << "frame " << frame_index << " block " << b << " quadrant "
                                 << quadrant;
        } else if (updates > 0) {
          ++passed_and_updated_quadrants;
        }
      }
      if (kept == 0) {
        ++rejected;
      } else if (kept != 0xFu) {
        ++partly_rejected;
      }
    }
  }
  EXPECT_GT(rejected, 3000u);
  EXPECT_GT(partly_rejected, 1000u);
  EXPECT_GT(passed_and_updated_quadrants, 8000u);
  EXPECT_GT(rejected_quadrants, 4 * rejected);
}

// The halves split a block's rows evenly, and a block of one voxel has one quadrant.
TEST(ProjectiveBlockScreen, HalvesCoverTheRows) {
  for (const int n : {1, 2, 8, 16}) {
    EXPECT_EQ(ProjectiveBlockScreen::halfBegin(n, 0), 0);
    EXPECT_EQ(ProjectiveBlockScreen::halfEnd(n, 0), ProjectiveBlockScreen::halfBegin(n, 1));
    EXPECT_EQ(ProjectiveBlockScreen::halfEnd(n, 1), n);
    EXPECT_EQ(ProjectiveBlockScreen::halfEnd(n, 0), (n + 1) / 2);
  }
}

}  // namespace
}  // namespace cblox
