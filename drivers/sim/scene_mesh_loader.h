#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/color.h"
#include "core/mesh/mesh.h"

namespace cblox {

/// What loadSceneMesh() accepts as simulator ground truth. Plain value type; every value is
/// valid (nothing to validate).
struct SceneMeshCheck {
  /// Accept meshes with edges shared by more than two triangles. Default true: scanned meshes
  /// are often non-manifold (double-sided faces, fins, internal faces) and render fine; such a
  /// mesh is accepted with a warning in SceneMeshReport::warnings, because "the surface" is
  /// ambiguous there for the ground-truth distance. Set false to refuse them (strict check).
  bool allow_non_manifold = true;
  /// Colour given to every vertex of a mesh without vertex colours, so that everything
  /// downstream (the renderer modulates it with its procedural texture; coloured ground-truth
  /// exports) sees one albedo. Default light grey (200, 200, 200), the renderer's own albedo
  /// for colourless meshes.
  Color default_color{200, 200, 200};
};

/// What loadSceneMesh() found, for logs and status.
struct SceneMeshReport {
  size_t vertices = 0;            ///< vertices of the returned mesh (as in the file)
  size_t triangles = 0;           ///< triangles of the returned mesh (degenerate ones dropped)
  size_t dropped_degenerate = 0;  ///< triangles with a repeated vertex or zero area, dropped
  size_t boundary_edges = 0;      ///< edges of exactly one triangle (open surfaces)
  size_t non_manifold_edges = 0;  ///< edges of three or more triangles (0 unless allowed)
  bool had_colors = false;        ///< the file had vertex colours (else default_color was used)
  /// Problems of an accepted mesh the user should hear about, one sentence each starting with
  /// "<path>: " (today: non-manifold edges, with their number and the first triangle).
  std::vector<std::string> warnings;
};

/// Loads a triangle mesh to be rendered by the simulator and used as its ground-truth surface.
/// The format follows the extension, case-insensitively: `.ply` (readPly) or `.obj` (readObj).
/// The mesh is then checked, in this order, and rejected (std::nullopt, `*error` set when not
/// null to a message starting with "<path>: ") when:
/// - the extension is neither, the file cannot be read or does not parse (the reader's
///   message, which names the line);
/// - it has no triangles: an empty file, or a point cloud (vertices without faces);
/// - it violates Mesh::validate(), or a vertex coordinate is not finite (NaN or infinite;
///   the message names the 0-based vertex index);
/// - no triangle is left after dropping degenerate ones;
/// - it has non-manifold edges (shared by more than two triangles) and
///   `options.allow_non_manifold` is false (not the default); the message gives the number of
///   such edges and the 0-based index (in the file's order, after polygon triangulation) of
///   the first triangle that has one.
/// With `allow_non_manifold` true (the default) a non-manifold mesh is accepted and the same
/// facts go into `report->warnings` (so pass a report to hear about it).
/// Degenerate triangles (a repeated vertex index or zero area) are dropped and counted, not
/// rejected. Normals (PLY) are kept. A mesh without vertex colours gets
/// `options.default_color` on every vertex. `report` (may be null) has every field overwritten
/// with the counts and warnings on success. Thread-safe (no shared state).
std::optional<Mesh> loadSceneMesh(const std::string& path, const SceneMeshCheck& options,
                                  std::string* error, SceneMeshReport* report = nullptr);

}  // namespace cblox
