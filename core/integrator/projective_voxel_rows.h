#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "core/geometry/color.h"
#include "core/integrator/tsdf_voxel_update.h"
#include "core/tsdf/voxel.h"

namespace cblox {

/// What the projective integrator reads per pixel, interleaved so one cache line serves both.
struct ProjectivePixelSample {
  float depth;       ///< the frame's depth, 0 where the pixel was rejected
  float ray_factor;  ///< ||(x_n, y_n, 1)|| of the pixel's normalised coordinates
};
static_assert(sizeof(ProjectivePixelSample) == 8, "the AVX2 rows load a sample as 8 bytes");

/// The voxel loop of ProjectiveTsdfIntegrator for one frame. A row of voxels (consecutive
/// in memory, centres p0 + i * step in the camera frame) is projected into the image, to
/// the nearest pixel, and each voxel whose pixel has a depth d and which lies no more than
/// the truncation behind it is updated by TsdfVoxelUpdater's rule with
/// sdf = (d - z) * ray_factor, weight measurementWeight(d) and the pixel's colour (black
/// when the frame has no colours but the rule blends them).
///
/// Two implementations with the same result bit for bit (tested):
/// - portable: four projections at a time (SSE2), then one voxel at a time;
/// - AVX2: eight voxels at a time, used where the CPU has AVX2 and the row length is a
///   multiple of 8: the projection, gathers of the pixel samples and colours, the update
///   rule and the colour blend run in eight lanes; the row's 12-byte voxels are split into
///   distances, weights and colours by shuffles and written back whole (a voxel not updated
///   is written back unchanged, so the caller must own the row, as the integrator's
///   threads own their blocks).
/// The arithmetic is the same in both, operation for operation and without fused
/// multiply-adds.
///
/// Thread safety: update() is const and may run concurrently on different rows.
class ProjectiveVoxelRows {
 public:
  /// One frame's image side. The pointers must outlive the object.
  struct Frame {
    float fx = 0.0f, fy = 0.0f;  ///< focal lengths, pixels
    float cx = 0.0f, cy = 0.0f;  ///< principal point, pixels
    int width = 0, height = 0;   ///< image size (SIMD paths: width * height < 2^24)
    const ProjectivePixelSample* samples = nullptr;  ///< width * height, row-major
    const Color* colors = nullptr;  ///< width * height, or null (colours not blended)
  };

  /// `vectorized`: use the AVX2 rows where the CPU has them (false: always the portable loop).
  ProjectiveVoxelRows(const Frame& frame, const TsdfVoxelUpdater& updater, bool vectorized);

  /// Updates row[0, count) (count <= kMaxRow); returns the number of voxels updated.
  size_t update(const Eigen::Vector3f& p0, const Eigen::Vector3f& step, int count,
                TsdfVoxel* row) const {
    return update(&p0, 1, step, count, row);
  }
  /// Updates `num_rows` rows of `count` voxels (count <= kMaxRow): row r is
  /// voxels[r * count, (r + 1) * count) with centres origins[r] + i * step. Returns the
  /// number of voxels updated. One call per block saves the per-row set-up.
  size_t update(const Eigen::Vector3f* origins, int num_rows, const Eigen::Vector3f& step,
                int count, TsdfVoxel* voxels) const;

  /// True when rows whose length is a multiple of 8 run on AVX2 (asked for, the CPU has it,
  /// and the image has fewer than 2^24 pixels).
  bool vectorized() const { return vectorized_; }

  static constexpr int kMaxRow = 64;

 private:
  size_t updatePortable(const Eigen::Vector3f& p0, const Eigen::Vector3f& step, int count,
                        TsdfVoxel* row) const;
  size_t updateAvx2(const Eigen::Vector3f* origins, int num_rows, const Eigen::Vector3f& step,
                    int count, TsdfVoxel* voxels) const;

  Frame frame_;
  TsdfVoxelUpdater updater_;
  float cx_rounding_, cy_rounding_;  // cx, cy + 0.5: the nearest pixel is a truncation
  bool vectorized_;
};

}  // namespace cblox
