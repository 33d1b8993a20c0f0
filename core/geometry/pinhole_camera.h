#pragma once

#include <string>

#include <Eigen/Core>

namespace cblox {

/// Pinhole intrinsics in pixels; image size in pixels. Pixel centres are at integer
/// coordinates: pixel (0, 0) covers [-0.5, 0.5) x [-0.5, 0.5).
struct PinholeIntrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
};

/// Returns an empty string if the intrinsics are usable, else a message naming the first bad
/// field, e.g. "fx must be > 0, got -1". Requires finite fx, fy > 0, finite cx, cy and
/// width, height > 0. Thread-safe (pure).
std::string validate(const PinholeIntrinsics& intrinsics);

/// Undistorted pinhole camera. The camera frame C has z forward, x right, y down (metres).
/// Immutable after construction: all member functions are thread-safe.
class PinholeCamera {
 public:
  /// Throws std::invalid_argument with validate()'s message if the intrinsics are invalid.
  explicit PinholeCamera(const PinholeIntrinsics& intrinsics);

  /// The intrinsics this camera was built with. Thread-safe.
  const PinholeIntrinsics& intrinsics() const { return intrinsics_; }
  /// Image width in pixels. Thread-safe.
  int width() const { return intrinsics_.width; }
  /// Image height in pixels. Thread-safe.
  int height() const { return intrinsics_.height; }

  /// Projects p_C (metres, camera frame) to pixel coordinates u = fx*x/z + cx,
  /// v = fy*y/z + cy. Returns false (leaving *uv unchanged) if z <= 0, any input is NaN, or
  /// the result falls outside [0, width) x [0, height). Note the accepted range is
  /// 0 <= u < width: std::floor(u) is always a valid column, std::lround(u) may equal width
  /// (use projectToPixel() for the nearest pixel). uv must be non-null. Thread-safe.
  bool project(const Eigen::Vector3d& p_C, Eigen::Vector2d* uv) const;

  /// Projects p_C (metres, camera frame) to the nearest pixel centre (round(u), round(v)).
  /// Returns false (leaving *u, *v unchanged) if z <= 0, any input is NaN, or the nearest
  /// pixel is outside the image. u and v must be non-null. Thread-safe.
  bool projectToPixel(const Eigen::Vector3d& p_C, int* u, int* v) const;

  /// Back-projects pixel coordinates uv to the camera-frame point with z == depth (metres):
  /// ((u - cx) / fx * depth, (v - cy) / fy * depth, depth). No range checks. Thread-safe.
  Eigen::Vector3d backProject(const Eigen::Vector2d& uv, double depth) const;

  /// Ray through pixel coordinates uv, scaled to z = 1: ((u - cx) / fx, (v - cy) / fy, 1).
  /// Not unit length. Thread-safe.
  Eigen::Vector3d rayDirection(const Eigen::Vector2d& uv) const;

  /// Intrinsics from a camera matrix K = [fx 0 cx; 0 fy cy; 0 0 1] and an image size (pixels).
  /// Throws std::invalid_argument if K has skew or a bottom row other than (0, 0, 1)
  /// (tolerance 1e-9 relative to fx). Does not validate the values (the constructor does).
  /// Thread-safe (pure).
  static PinholeIntrinsics fromK(const Eigen::Matrix3d& K, int width, int height);

 private:
  PinholeIntrinsics intrinsics_;
};

}  // namespace cblox
