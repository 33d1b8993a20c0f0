#pragma once

// A mesh seen by height: which way is up, how high each vertex lies. For pictures of maps
// whose frame is not z-up (a camera's frame G: y down).

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mesh/mesh.h"

namespace cblox {

/// "x", "y", "z", "-x", "-y" or "-z" as the unit axis it names, or std::nullopt for anything
/// else. Thread-safe (pure).
std::optional<Eigen::Vector3d> parseUpAxis(const std::string& text);

/// The rotation that turns the unit axis `up` into +z: about x for +-y, about y for +-x, a
/// half turn about x for -z, none for +z; its entries are exactly 0, 1 or -1. Throws
/// std::invalid_argument when `up` is not one of the six axes. Thread-safe (pure).
Eigen::Matrix3d upTurn(const Eigen::Vector3d& up);

/// `mesh` turned so that the unit axis `up` becomes +z (upTurn(up)), applied to vertices and
/// normals; colours and triangles are kept. Throws std::invalid_argument when `up` is not one
/// of the six axes. Thread-safe (pure).
Mesh turnedUp(const Mesh& mesh, const Eigen::Vector3d& up);

/// Per-vertex height along the unit vector `up` above the lowest vertex: up . v_i -
/// min_j up . v_j (>= 0; empty for a mesh without vertices). Thread-safe (pure).
std::vector<double> vertexHeights(const Mesh& mesh, const Eigen::Vector3d& up);

}  // namespace cblox
