#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "core/integrator/integration_stats.h"

namespace cblox {

/// A point the ray-casting integrators accept: its index in the cloud and the packed
/// (packGridIndex) index of its start cell in the layer frame.
struct ScreenedPoint {
  uint32_t index;
  uint64_t cell;
};

/// The per-point checks of RayCastingIntegrator before a ray is cast, for a run of
/// consecutive points of a cloud in the sensor frame C:
/// - invalid: a coordinate is not finite, or the sensor or the point in the layer frame G
///   lies outside the packable grid (|coordinate| >= coordinate_limit);
/// - out of range: the squared ray length x*x + y*y + z*z is below min_length_squared or
///   above max_length_squared;
/// - otherwise accepted, with its start cell floor(p_G * cell_size_inv) per axis (fast mode).
/// p_G = R_G_C * p_C + t_G_C is computed row by row as ((r0 * x + r1 * y) + r2 * z) + t.
///
/// Two implementations with the same result bit for bit (tested): one point at a time, and
/// eight at a time on AVX2 where the CPU has it. Both evaluate the same float operations
/// in the same order, without fused multiply-adds (the file is built with
/// -ffp-contract=off).
///
/// Thread safety: screen() is const and may run concurrently.
class RayPointScreen {
 public:
  struct Frame {
    Eigen::Matrix3f R_G_C;
    Eigen::Vector3f t_G_C;
    float min_length_squared = 0.0f;
    float max_length_squared = 0.0f;
    float coordinate_limit = 0.0f;  ///< bound on |p_G| per axis (and on the sensor's)
    float cell_size_inv = 1.0f;     ///< start cells: cells of this inverse size
  };

  /// `vectorized`: use AVX2 where the CPU has it (false: one point at a time).
  RayPointScreen(const Frame& frame, bool vectorized);

  /// Screens points[0, count), whose cloud indices start at `first_index`; writes the
  /// accepted ones in order to `accepted` (room for `count`) and returns how many; adds the
  /// rejected ones to stats->points_invalid and stats->points_out_of_range.
  size_t screen(const Eigen::Vector3f* points, uint32_t first_index, size_t count,
                ScreenedPoint* accepted, IntegrationStats* stats) const;

  bool vectorized() const { return vectorized_; }

 private:
  size_t screenPortable(const Eigen::Vector3f* points, uint32_t first_index, size_t count,
                        ScreenedPoint* accepted, IntegrationStats* stats) const;
  size_t screenAvx2(const Eigen::Vector3f* points, uint32_t first_index, size_t count,
                    ScreenedPoint* accepted, IntegrationStats* stats) const;

  Frame frame_;
  bool origin_in_range_;
  bool vectorized_;
};

}  // namespace cblox
