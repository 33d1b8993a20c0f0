#pragma once

#include <optional>
#include <span>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/geometry/color.h"
#include "core/geometry/image.h"
#include "core/mesh/mesh.h"

namespace cblox {

/// A pinhole camera placed at `eye` looking at `look_at` (metres, in the mesh's frame), with
/// the world z axis up in the image (the world y axis when the view is along z).
struct MeshViewpoint {
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  Eigen::Vector3d look_at = Eigen::Vector3d::UnitX();
};

/// Options of renderMeshError() and writeMeshErrorPng(). Plain value type.
struct MeshErrorRenderConfig {
  int width = 1024;                ///< pixels, in [200, 10000]
  int height = 768;                ///< pixels, in [150, 10000]
  double vertical_fov_deg = 45.0;  ///< in [10, 120]
  /// std::nullopt: automaticViewpoint() of the mesh's bounds.
  std::optional<MeshViewpoint> viewpoint;
  /// Errors are coloured by colormap(error / max_error_m): 0 dark purple, >= max_error_m
  /// yellow (larger and infinite errors saturate). Finite and > 0.
  double max_error_m = 0.05;
  /// Labels the colour bar in millimetres ("mm", values * 1000) or metres ("m").
  bool millimetres = true;
  /// Triangles seen from behind (geometric normal (v1 - v0) x (v2 - v0) pointing away from
  /// the camera) are see-through, so a room reconstructed from inside can be looked into
  /// from outside (its ceiling and near walls face inwards). Open surfaces seen from their
  /// back disappear; turn off to see every triangle.
  bool cull_back_faces = true;
  /// n x n rays per pixel (anti-aliasing), in [1, 4].
  int supersampling = 2;
  /// One line centred above the picture; none if empty.
  std::string title;
  /// Fills the whole picture (behind the mesh, the colour bar and the title).
  Color background{235, 235, 235};
  /// Threads for the rays, in [1, 64]. The picture does not depend on it.
  int num_threads = 2;

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// A viewpoint from which all of `bounds` (metres) is seen: looking at the box's centre from
/// above and to the side (azimuth -60 degrees from +x towards +y, i.e. from the +x -y side,
/// elevation 35 degrees), at the smallest distance at which all eight box corners project
/// inside 92 % of a picture with the given vertical field of view and aspect (width /
/// height). An empty box gives a viewpoint 1 m from the origin; a single point, one 1 m from
/// it. Thread-safe (pure).
MeshViewpoint automaticViewpoint(const Eigen::AlignedBox3d& bounds, double vertical_fov_deg,
                                 double aspect);

/// Renders `mesh` coloured by its per-vertex errors (`vertex_errors_m`, one per vertex,
/// metres; non-negative, +infinity allowed; e.g. MeshAccuracy::vertex_errors_m) with the
/// same Embree ray tracer as the rest of cblox: one ray per sub-pixel from the viewpoint; at
/// a hit the error is interpolated from the triangle's three vertices with the hit's
/// barycentric coordinates (each vertex error first clamped to max_error_m), coloured by
/// colormap(), and shaded by a headlight: colour * (0.6 + 0.4 * |cos|) with cos the angle
/// between the ray and the triangle's normal. Pixels without a hit take the background. The
/// mesh fills the picture left of a colour bar (drawColorBar(), 0 .. max_error_m in mm or m,
/// in the rightmost 110 px), under the title (40 px) when there is one. Returns std::nullopt
/// with a message when the options are invalid, the mesh has no triangle or is malformed
/// (Mesh::validate, non-finite vertex), vertex_errors_m has the wrong size or a negative or
/// NaN entry, or the viewpoint's eye equals its look_at point. Thread-safe (pure; uses
/// options.num_threads threads).
std::optional<ColorImage> renderMeshError(const Mesh& mesh, std::span<const double> vertex_errors_m,
                                          const MeshErrorRenderConfig& options,
                                          std::string* error);

/// renderMeshError() written as an 8-bit RGB PNG file to `path` (writeColorImagePng()).
/// Returns false with a message (naming the path when writing fails) on the errors of
/// renderMeshError() or when the file cannot be written. Thread-safe (no shared state;
/// concurrent writes to the same path race in the file system).
bool writeMeshErrorPng(const std::string& path, const Mesh& mesh,
                       std::span<const double> vertex_errors_m,
                       const MeshErrorRenderConfig& options, std::string* error);

}  // namespace cblox
