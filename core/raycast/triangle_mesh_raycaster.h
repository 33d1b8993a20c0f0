#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/geometry/pinhole_camera.h"
#include "core/mesh/mesh.h"

struct RTCRayHit16;  // Embree's 16-ray packet (embree3/rtcore_ray.h)

namespace cblox {

/// One ray: origin + t * direction for t in [t_near, t_far]. The direction need not be unit
/// length; distances are then in units of its length (a camera ray scaled to z = 1 returns
/// the z depth directly).
struct Ray {
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();
  float t_near = 0.0f;
  float t_far = std::numeric_limits<float>::infinity();
};

/// First intersection of a ray with the mesh.
struct RaycastHit {
  static constexpr uint32_t kNoHit = std::numeric_limits<uint32_t>::max();

  float t = std::numeric_limits<float>::infinity();  ///< ray parameter of the hit
  uint32_t triangle = kNoHit;                        ///< index into Mesh::triangles
  /// Barycentric coordinates of the hit: point = (1 - u - v) * v0 + u * v1 + v * v2.
  float u = 0.0f, v = 0.0f;
  /// Unit geometric normal (v1 - v0) x (v2 - v0) / |...| of the triangle hit (not flipped
  /// towards the ray; precomputed per triangle).
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();

  bool hit() const { return triangle != kNoHit; }
};

/// Closest point of the mesh surface to a query point.
struct ClosestSurfacePoint {
  double distance = std::numeric_limits<double>::infinity();  ///< metres; inf if none in range
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  uint32_t triangle = RaycastHit::kNoHit;

  bool found() const { return triangle != RaycastHit::kNoHit; }
};

/// Ray casting and closest-point queries on a static triangle mesh, backed by Embree 3 (a
/// BVH built once at construction). Ray hits are Embree's watertight single-precision
/// intersections; closest points are computed exactly (double precision point-to-triangle
/// distance) on the triangles Embree's BVH traversal proposes.
///
/// Thread-safety: immutable after create(); every query method is thread-safe and may be
/// called concurrently from any number of threads.
class TriangleMeshRaycaster {
 public:
  /// Builds the acceleration structure for `mesh` (its vertices and triangles are copied).
  /// Returns nullptr and writes a message to *error (when non-null) if the mesh violates its
  /// invariants (Mesh::validate), has no triangle, has a non-finite vertex, or Embree fails
  /// (the message includes Embree's). Degenerate (zero-area) triangles are allowed: rays
  /// never hit them and closest-point queries treat them as segments. Thread-safe.
  static std::unique_ptr<TriangleMeshRaycaster> create(const Mesh& mesh, std::string* error);

  ~TriangleMeshRaycaster();
  TriangleMeshRaycaster(const TriangleMeshRaycaster&) = delete;
  TriangleMeshRaycaster& operator=(const TriangleMeshRaycaster&) = delete;

  /// First hit of `ray` in [t_near, t_far]; returns hit.hit(). Thread-safe.
  bool intersect(const Ray& ray, RaycastHit* hit) const;

  /// First hits of many rays (hits.size() >= rays.size()), traced in packets of 16; fastest
  /// when neighbouring rays are coherent (e.g. adjacent pixels). Thread-safe.
  void intersect(std::span<const Ray> rays, std::span<RaycastHit> hits) const;

  /// First hits of the rays of a pinhole camera (pose R_G_C, origin_G) through the pixel
  /// centres of rows [row_begin, row_end): direction R_G_C * ((u - cx) / fx, (v - cy) / fy, 1),
  /// so t is the depth along the camera's z. hits (size >= (row_end - row_begin) * width) is
  /// row-major from row_begin. Traced in 4 x 4 pixel packets. Thread-safe.
  void intersectPinholeRows(const Eigen::Matrix3f& R_G_C, const Eigen::Vector3f& origin_G,
                            const PinholeIntrinsics& intrinsics, int row_begin, int row_end,
                            std::span<RaycastHit> hits) const;

  /// True if anything lies on `ray` within [t_near, t_far] (shadow ray). Thread-safe.
  bool occluded(const Ray& ray) const;

  /// Closest point of the surface to `p` within max_distance (metres); not found() when
  /// nothing is that close. Thread-safe.
  ClosestSurfacePoint closestPoint(
      const Eigen::Vector3d& p,
      double max_distance = std::numeric_limits<double>::infinity()) const;

  /// The mesh the structure was built from (vertex colours and normals included). Thread-safe.
  const Mesh& mesh() const { return mesh_; }

  /// Axis-aligned bounds of the vertices. Thread-safe.
  const Eigen::AlignedBox3f& bounds() const { return bounds_; }

 private:
  struct EmbreeHandles;

  TriangleMeshRaycaster() = default;
  /// Traces a prepared packet and converts its first `count` lanes to hits.
  void tracePacket(::RTCRayHit16* packet, const int* valid, size_t count,
                   RaycastHit* hits) const;

  Mesh mesh_;
  std::vector<Eigen::Vector3f> triangle_normals_;
  Eigen::AlignedBox3f bounds_;
  std::unique_ptr<EmbreeHandles> embree_;
};

}  // namespace cblox
