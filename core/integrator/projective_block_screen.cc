#include "core/integrator/projective_block_screen.h"

#include <cstring>
#include <limits>
#include <stdexcept>

namespace cblox {
namespace {

// GCC/Clang vector extensions: the four quadrants in the four lanes, on any target.
typedef float Float4 __attribute__((vector_size(16)));
typedef int Int4 __attribute__((vector_size(16)));

Float4 load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
Float4 min4(Float4 a, Float4 b) { return a < b ? a : b; }
Float4 max4(Float4 a, Float4 b) { return a > b ? a : b; }
Int4 minInt4(Int4 a, Int4 b) { return a < b ? a : b; }
Int4 maxInt4(Int4 a, Int4 b) { return a > b ? a : b; }

}  // namespace

ProjectiveBlockScreen::ProjectiveBlockScreen(const Frame& frame) : frame_(frame) {
  if (frame.cell_pixels < 1 || (frame.cell_pixels & (frame.cell_pixels - 1)) != 0) {
    throw std::invalid_argument("ProjectiveBlockScreen: cell_pixels must be a power of two");
  }
  cell_shift_ = __builtin_ctz(static_cast<unsigned>(frame.cell_pixels));
  const int n = frame.voxels_per_side;
  for (int q = 0; q < 4; ++q) {
    const int y_half = q & 1, z_half = q >> 1;
    const int y0 = halfBegin(n, y_half), y1 = halfEnd(n, y_half) - 1;
    const int z0 = halfBegin(n, z_half), z1 = halfEnd(n, z_half) - 1;
    if (y1 >= y0 && z1 >= z0) nonempty_ |= 1u << q;
    for (int corner = 0; corner < 8; ++corner) {
      // Voxel offsets of the corner centre along the block's axes.
      const Eigen::Vector3f voxels(static_cast<float>(corner & 1 ? n - 1 : 0),
                                   static_cast<float>(corner & 2 ? y1 : y0),
                                   static_cast<float>(corner & 4 ? z1 : z0));
      const Eigen::Vector3f offset = frame.R_C_G * (voxels * frame.voxel_size);
      offset_x_[4 * corner + q] = offset.x();
      offset_y_[4 * corner + q] = offset.y();
      offset_z_[4 * corner + q] = offset.z();
    }
  }
}

unsigned ProjectiveBlockScreen::rowQuadrants(const Eigen::Vector3f& origin) const {
  const Eigen::Vector3f first =
      frame_.R_C_G * (origin + Eigen::Vector3f::Constant(0.5f * frame_.voxel_size)) + frame_.t_C_G;
  // Each quadrant's nearest corner depth and the bounding box of its corners' projections,
  // the four quadrants at once.
  const Float4 x0 = Float4{} + first.x(), y0 = Float4{} + first.y(), z0 = Float4{} + first.z();
  const Float4 fx = Float4{} + frame_.fx, fy = Float4{} + frame_.fy;
  const Float4 cx = Float4{} + frame_.cx, cy = Float4{} + frame_.cy;
  const Float4 near = Float4{} + 1e-3f, one = Float4{} + 1.0f;
  const float inf = std::numeric_limits<float>::infinity();
  Float4 z_min = Float4{} + inf, u_min = z_min, v_min = z_min;
  Float4 u_max = Float4{} - inf, v_max = u_max;
  for (int corner = 0; corner < 8; ++corner) {
    const Float4 z = z0 + load4(offset_z_ + 4 * corner);
    const Float4 inv_z = one / (z > near ? z : near);
    const Float4 u = fx * (x0 + load4(offset_x_ + 4 * corner)) * inv_z + cx;
    const Float4 v = fy * (y0 + load4(offset_y_ + 4 * corner)) * inv_z + cy;
    z_min = min4(z_min, z);
    u_min = min4(u_min, u);
    u_max = max4(u_max, u);
    v_min = min4(v_min, v);
    v_max = max4(v_max, v);
  }
  // The voxels' nearest pixels, with one pixel of margin for rounding. Clamped to [-2, size]
  // first, so that the conversion is safe and floor(x) is the truncation of x + 2, less 2.
  const Float4 low = Float4{} - 2.0f, two = Float4{} + 2.0f;
  const Float4 w = Float4{} + static_cast<float>(frame_.width);
  const Float4 h = Float4{} + static_cast<float>(frame_.height);
  const auto floorPlus2 = [&](Float4 x, Float4 size) {
    return __builtin_convertvector(min4(max4(x, low), size) + two, Int4);
  };
  const Int4 zero_i = Int4{};
  const Int4 u0 = maxInt4(floorPlus2(u_min, w) - 3, zero_i);
  const Int4 u1 = minInt4(floorPlus2(u_max, w) - 1, Int4{} + (frame_.width - 1));
  const Int4 v0 = maxInt4(floorPlus2(v_min, h) - 3, zero_i);
  const Int4 v1 = minInt4(floorPlus2(v_max, h) - 1, Int4{} + (frame_.height - 1));
  unsigned quadrants = 0;
  for (int q = 0; q < 4; ++q) {
    if (!(nonempty_ & (1u << q))) continue;
    if (!(z_min[q] > 1e-3f)) {  // a corner near or behind the camera plane: not bounded here
      quadrants |= 1u << q;
      continue;
    }
    if (u0[q] > u1[q] || v0[q] > v1[q]) continue;  // the quadrant projects outside the image
    const float d_max = frame_.cell_max_depth->max(u0[q] >> cell_shift_, u1[q] >> cell_shift_,
                                                   v0[q] >> cell_shift_, v1[q] >> cell_shift_);
    if (d_max <= 0.0f) continue;  // no valid pixel under the quadrant
    // A margin of 0.01 % + 0.1 mm for the float rounding of the voxel loop.
    if (!(z_min[q] > (d_max + frame_.truncation) * 1.0001f + 1e-4f)) quadrants |= 1u << q;
  }
  return quadrants;
}

}  // namespace cblox
