#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include <Eigen/Core>

namespace cblox {

/// Whether any voxel of a block can be updated by a frame of the projective integrator,
/// from the block's corners and the deepest valid depth of each cell of pixels. A voxel is updated
/// only where its nearest pixel has a depth d with (d - z) * ray_factor >= -truncation, and
/// ray_factor >= 1, so never where z > d + truncation. The voxel centres lie in the cube of the
/// eight corner centres, so (in front of the camera) their depths lie between the corners' and
/// their projections within the corners' bounding box.
struct ProjectiveBlockScreen {
  Eigen::Matrix3f R_C_G;
  Eigen::Vector3f t_C_G;
  float fx, fy, cx, cy;  // cx, cy with the +0.5 of rounding to the nearest pixel
  int width, height;
  float first_centre;  // from the block's origin to its first voxel centre, per axis
  float centre_span;   // from the first to the last voxel centre, per axis
  float truncation;
  const float* cell_max_depth;  // per cell of cell_pixels^2 pixels, 0 where none is valid
  int cells_x;                  // cells per image row
  int cell_pixels;

  /// False only when no voxel of the block whose origin (minimum corner) is `origin` can
  /// be updated. Thread-safe (const).
  bool mayUpdate(const Eigen::Vector3f& origin) const {
    float z_min = std::numeric_limits<float>::infinity();
    float u_min = z_min, v_min = z_min, u_max = -z_min, v_max = -z_min;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3f p =
          origin + Eigen::Vector3f(corner & 1 ? first_centre + centre_span : first_centre,
                                   corner & 2 ? first_centre + centre_span : first_centre,
                                   corner & 4 ? first_centre + centre_span : first_centre);
      const Eigen::Vector3f c = R_C_G * p + t_C_G;
      if (!(c.z() > 1e-3f)) return true;  // near or behind the camera plane: not bounded here
      z_min = std::min(z_min, c.z());
      const float u = fx * c.x() / c.z() + cx, v = fy * c.y() / c.z() + cy;
      u_min = std::min(u_min, u);
      u_max = std::max(u_max, u);
      v_min = std::min(v_min, v);
      v_max = std::max(v_max, v);
    }
    // The voxels' nearest pixels, with one pixel of margin for rounding.
    const int u0 = std::max(0, static_cast<int>(std::floor(u_min)) - 1);
    const int u1 = std::min(width - 1, static_cast<int>(std::floor(u_max)) + 1);
    const int v0 = std::max(0, static_cast<int>(std::floor(v_min)) - 1);
    const int v1 = std::min(height - 1, static_cast<int>(std::floor(v_max)) + 1);
    if (u0 > u1 || v0 > v1) return false;  // the whole block projects outside the image
    float d_max = 0.0f;
    for (int cv = v0 / cell_pixels; cv <= v1 / cell_pixels; ++cv) {
      for (int cu = u0 / cell_pixels; cu <= u1 / cell_pixels; ++cu) {
        d_max = std::max(d_max, cell_max_depth[static_cast<size_t>(cv) * cells_x + cu]);
      }
    }
    if (d_max <= 0.0f) return false;  // no valid pixel under the block
    // A margin of 0.01 % + 0.1 mm for the float rounding of the voxel loop.
    return !(z_min > (d_max + truncation) * 1.0001f + 1e-4f);
  }
};

}  // namespace cblox
