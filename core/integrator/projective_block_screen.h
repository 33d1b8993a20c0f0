#pragma once

#include <Eigen/Core>

#include "core/integrator/rectangle_max_table.h"

namespace cblox {

/// Which voxel rows of a block a frame of the projective integrator can update, from the
/// corners of the block's parts and the deepest valid depth of each cell of pixels.
///
/// A block's rows of voxels run along x; they are split into four quadrants by halving the
/// y and z voxel indices: quadrant q = 2 * z_half + y_half holds the rows j in y_half's
/// range and k in z_half's, the lower half of n = voxels_per_side being [0, ceil(n / 2))
/// and the upper [ceil(n / 2), n) (empty when n = 1).
///
/// A voxel is updated only where its nearest pixel has a depth d with
/// (d - z) * ray_factor >= -truncation, and ray_factor >= 1, so never where z > d + truncation.
/// The voxel centres of a quadrant lie in the box of its eight corner centres, so (in front of
/// the camera) their depths lie between the corners' and their projections within the
/// corners' bounding box. A quadrant is rejected when that box projects outside the image,
/// sees only pixels without depth, or its nearest corner is more than the truncation behind
/// the deepest pixel of the 8x8-pixel cells under it.
class ProjectiveBlockScreen {
 public:
  /// One frame's side of the screen. The cell table must outlive the screen.
  struct Frame {
    Eigen::Matrix3f R_C_G;
    Eigen::Vector3f t_C_G;
    float fx, fy, cx, cy;  ///< cx, cy with the +0.5 of rounding to the nearest pixel
    int width, height;
    float voxel_size;
    int voxels_per_side;
    float truncation;
    /// The deepest valid depth per cell of cell_pixels^2 pixels, 0 where none is valid.
    const RectangleMaxTable* cell_max_depth;
    int cell_pixels;  ///< a power of two
  };

  /// Throws std::invalid_argument when cell_pixels is not a power of two.
  explicit ProjectiveBlockScreen(const Frame& frame);

  /// Bit q set when a voxel of quadrant q of the block whose origin (minimum corner) is
  /// `origin` may be updated; 0 when no voxel of the block can be. Thread-safe (const).
  unsigned rowQuadrants(const Eigen::Vector3f& origin) const;
  /// The quadrants that hold rows: 0xF, or 0x1 for blocks of one voxel.
  unsigned nonemptyQuadrants() const { return nonempty_; }

  /// The rows [begin, end) of y (or z) half `half` (0 or 1) of a block of
  /// `voxels_per_side` voxels per side.
  static int halfBegin(int voxels_per_side, int half) {
    return half == 0 ? 0 : (voxels_per_side + 1) / 2;
  }
  static int halfEnd(int voxels_per_side, int half) {
    return half == 0 ? (voxels_per_side + 1) / 2 : voxels_per_side;
  }

 private:
  static constexpr int kCorners = 32;  // 8 per quadrant

  Frame frame_;
  // The quadrants' corner centres relative to the block's first voxel centre, in the camera
  // frame: corner c of quadrant q at 4c + q, so that the quadrants fill the lanes of a vector.
  alignas(16) float offset_x_[kCorners], offset_y_[kCorners], offset_z_[kCorners];
  unsigned nonempty_ = 0;  // the quadrants that hold rows
  int cell_shift_ = 0;     // log2(cell_pixels)
};

}  // namespace cblox
