#include "drivers/sim/scene_mesh_loader.h"

#include <cctype>
#include <filesystem>
#include <sstream>
#include <utility>
#include <vector>

#include "core/io/obj_io.h"
#include "core/io/ply_io.h"
#include "core/mesh/mesh_topology.h"

namespace cblox {
namespace {

std::optional<Mesh> fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return std::nullopt;
}

std::string lowerCase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// Same criterion as analyzeTopology(): a repeated index or zero (or NaN) area.
bool isDegenerate(const Mesh& mesh, const Eigen::Vector3i& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Eigen::Vector3f& a = mesh.vertices[static_cast<size_t>(t[0])];
  const float area2 = (mesh.vertices[static_cast<size_t>(t[1])] - a)
                          .cross(mesh.vertices[static_cast<size_t>(t[2])] - a)
                          .squaredNorm();
  return !(area2 > 0.0f);
}

}  // namespace

std::optional<Mesh> loadSceneMesh(const std::string& path, const SceneMeshCheck& options,
                                  std::string* error, SceneMeshReport* report) {
  const std::string extension = lowerCase(std::filesystem::path(path).extension().string());
  Mesh mesh;
  std::string read_error;
  if (extension == ".ply") {
    if (!readPly(path, &mesh, &read_error)) return fail(error, read_error);
  } else if (extension == ".obj") {
    if (!readObj(path, &mesh, &read_error)) return fail(error, read_error);
  } else {
    const std::string found = extension.empty() ? "no extension" : "extension '" + extension + "'";
    return fail(error, path + ": unsupported scene mesh file (" + found +
                           "), expected .ply or .obj (any case)");
  }

  if (mesh.numTriangles() == 0) {
    if (mesh.numVertices() == 0) {
      return fail(error, path +
                             ": the file holds no vertices and no triangles; a scene mesh "
                             "needs triangles");
    }
    return fail(error, path + ": the file is a point cloud (" + std::to_string(mesh.numVertices()) +
                           " vertices, no faces); a scene mesh needs triangles");
  }
  const std::string invalid = mesh.validate();
  if (!invalid.empty()) return fail(error, path + ": invalid mesh: " + invalid);
  for (size_t i = 0; i < mesh.numVertices(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      std::ostringstream msg;
      msg << path << ": vertex " << i << " (0-based) is not finite: (" << mesh.vertices[i].x()
          << ", " << mesh.vertices[i].y() << ", " << mesh.vertices[i].z() << ")";
      return fail(error, msg.str());
    }
  }

  // Drop degenerate triangles, remembering the file index of each kept one for messages.
  std::vector<size_t> file_index;
  file_index.reserve(mesh.numTriangles());
  size_t kept = 0;
  for (size_t i = 0; i < mesh.numTriangles(); ++i) {
    if (isDegenerate(mesh, mesh.triangles[i])) continue;
    mesh.triangles[kept++] = mesh.triangles[i];
    file_index.push_back(i);
  }
  const size_t dropped = mesh.numTriangles() - kept;
  if (kept == 0) {
    return fail(error, path + ": all " + std::to_string(dropped) +
                           " triangles are degenerate (a repeated vertex or zero area)");
  }
  mesh.triangles.resize(kept);

  const MeshTopology topology = analyzeTopology(mesh);
  std::vector<std::string> warnings;
  if (topology.non_manifold_edges > 0) {
    const size_t first = file_index[static_cast<size_t>(topology.first_non_manifold_triangle)];
    const std::string facts =
        path + ": " + std::to_string(topology.non_manifold_edges) +
        " non-manifold edge(s) (shared by more than two triangles, e.g. double-sided faces); the "
        "first is on triangle " +
        std::to_string(first) + " (0-based, in file order after polygon triangulation)";
    if (!options.allow_non_manifold) {
      return fail(error, facts + "; set allow_non_manifold to accept such a mesh");
    }
    warnings.push_back(facts +
                       "; accepted, but the ground-truth surface is ambiguous near those edges");
  }

  const bool had_colors = mesh.hasColors();
  if (!had_colors) mesh.colors.assign(mesh.numVertices(), options.default_color);
  if (report != nullptr) {
    report->vertices = mesh.numVertices();
    report->triangles = mesh.numTriangles();
    report->dropped_degenerate = dropped;
    report->boundary_edges = topology.boundary_edges;
    report->non_manifold_edges = topology.non_manifold_edges;
    report->had_colors = had_colors;
    report->warnings = std::move(warnings);
  }
  return mesh;
}

}  // namespace cblox
