#pragma once

#include <string>
#include <variant>

#include <Eigen/Core>

#include "core/geometry/color.h"
#include "drivers/synthetic/texture.h"

namespace cblox {

// Analytic scene primitives, all in the global frame G (metres). Every primitive has a
// surface, a signed distance to that surface and a procedural colour on it. The sign
// convention is the same for all: positive on the free-space side, negative inside matter.
// Plain value types; thread-safe to read concurrently.

/// Infinite plane through `point` with unit `normal`; the free side is the one the normal
/// points to (a ground plane z = 0 has normal +z). Checker coordinates: an orthonormal
/// basis of the plane, origin at `point`.
struct Plane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  CheckerTexture texture;
};

/// Solid sphere. Checker coordinates: (radius * azimuth, radius * elevation).
struct Sphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 1.0;
  CheckerTexture texture;
};

/// Solid axis-aligned box (furniture): free space is outside. Checker coordinates on each
/// face: the two global coordinates spanning that face.
struct SolidBox {
  Eigen::Vector3d min_corner = -Eigen::Vector3d::Ones();
  Eigen::Vector3d max_corner = Eigen::Vector3d::Ones();
  CheckerTexture texture;
};

/// Axis-aligned box seen from inside (a room: floor, ceiling and walls): free space is
/// inside. Checker coordinates as for SolidBox.
struct Room {
  Eigen::Vector3d min_corner = -Eigen::Vector3d::Ones();
  Eigen::Vector3d max_corner = Eigen::Vector3d::Ones();
  CheckerTexture texture;
};

/// Solid capped cylinder with a vertical (z) axis through (axis_x, axis_y), spanning
/// z_min..z_max. Checker coordinates: (radius * azimuth, z) on the side, (x, y) on the caps.
struct Cylinder {
  double axis_x = 0.0;
  double axis_y = 0.0;
  double radius = 1.0;
  double z_min = 0.0;
  double z_max = 1.0;
  CheckerTexture texture;
};

using Primitive = std::variant<Plane, Sphere, SolidBox, Room, Cylinder>;

/// Returns an empty string if the primitive is well formed, else a message naming the
/// problem (non-finite values, zero normal, radius <= 0, min corner not below max corner).
/// A plane's normal need not be unit length here; AnalyticScene normalises it. Thread-safe.
std::string validate(const Primitive& primitive);

/// Nearest intersection of the ray origin + t * dir (dir unit length) with the primitive's
/// surface, for t in (0, t_max]. Hits the surface from either side (a ray starting inside a
/// solid sees its inner face). Returns false if there is none; *t is then unchanged.
/// Thread-safe (pure).
bool intersect(const Primitive& primitive, const Eigen::Vector3d& origin,
               const Eigen::Vector3d& dir, double t_max, double* t);

/// Exact signed Euclidean distance (metres) from p to the primitive's surface: positive on
/// the free side (outside solids, inside the room, on the normal side of a plane), negative
/// inside matter, 0 on the surface. Thread-safe (pure).
double signedDistance(const Primitive& primitive, const Eigen::Vector3d& p);

/// Procedural colour of the surface at p (p is assumed to lie on the surface; for other
/// points the colour of a nearby surface point is returned). Thread-safe (pure).
Color surfaceColor(const Primitive& primitive, const Eigen::Vector3d& p);

}  // namespace cblox
