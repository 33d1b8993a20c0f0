#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/geometry/color.h"
#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "drivers/synthetic/primitives.h"

namespace cblox {

/// A scene made of analytic primitives (planes, spheres, solid boxes, a room, cylinders) in
/// the global frame G (metres) with exact ray casting and signed distance: ground truth for
/// tests and a stand-in capture source for the demo.
///
/// Thread-safety: add() mutates and needs exclusive access; every const member function is
/// thread-safe (the scene is only read).
class AnalyticScene {
 public:
  AnalyticScene() = default;

  /// Adds a primitive. A plane's normal is normalised. Throws std::invalid_argument with
  /// validate()'s message if the primitive is malformed. Not thread-safe.
  void add(Primitive primitive);

  /// The primitives, in insertion order. Thread-safe.
  const std::vector<Primitive>& primitives() const { return primitives_; }

  /// Exact nearest intersection of the ray origin_G + t * dir_G with any primitive surface,
  /// for t in (0, max_range]. dir_G should be unit length; it is normalised here, so *range is
  /// always the Euclidean distance (metres) from origin_G to the hit. Surfaces are hit from
  /// either side. On a hit writes *range and, if color is non-null, the surface colour, and
  /// returns true; otherwise returns false and leaves both untouched. range must be non-null.
  /// Thread-safe.
  bool raycast(const Eigen::Vector3d& origin_G, const Eigen::Vector3d& dir_G, double max_range,
               double* range, Color* color = nullptr) const;

  /// Signed distance (metres) from p_G to the nearest primitive surface. Magnitude: the exact
  /// Euclidean distance to the closest surface of any primitive (where primitives overlap,
  /// surface parts buried inside another primitive count too, so it never over-estimates
  /// the distance to the visible surface). Sign: negative if p_G is inside matter for any
  /// primitive (inside a solid sphere/box/cylinder, outside the room, behind a plane), else
  /// positive (free space); 0 on a surface. +infinity for an empty scene. Thread-safe.
  double signedDistance(const Eigen::Vector3d& p_G) const;

  /// Renders the scene from a camera at T_G_C. Resizes *depth (and *color, if non-null) to the
  /// camera's size. depth(u, v) is the camera-frame z coordinate (metres, not the range) of
  /// the nearest hit along the ray through the pixel centre (u, v); 0 if there is no hit
  /// within max_range, where max_range bounds the Euclidean range along the ray. color(u, v)
  /// is the hit's surface colour, black for no hit. Renders rows in 2 std::threads.
  /// Throws std::invalid_argument if depth is null or max_range is not > 0. Thread-safe with
  /// respect to the scene; the output images must not be shared with other threads.
  void renderDepth(const Transformationd& T_G_C, const PinholeCamera& camera, DepthImage* depth,
                   ColorImage* color, double max_range) const;

 private:
  std::vector<Primitive> primitives_;
};

}  // namespace cblox
