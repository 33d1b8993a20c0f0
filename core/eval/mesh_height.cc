#include "core/eval/mesh_height.h"

#include <algorithm>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>

namespace cblox {

std::optional<Eigen::Vector3d> parseUpAxis(const std::string& text) {
  const bool negative = !text.empty() && text[0] == '-';
  const std::string axis = negative ? text.substr(1) : text;
  Eigen::Vector3d up;
  if (axis == "x") {
    up = Eigen::Vector3d::UnitX();
  } else if (axis == "y") {
    up = Eigen::Vector3d::UnitY();
  } else if (axis == "z") {
    up = Eigen::Vector3d::UnitZ();
  } else {
    return std::nullopt;
  }
  return negative ? Eigen::Vector3d(-up) : up;
}

Eigen::Matrix3d upTurn(const Eigen::Vector3d& up) {
  Eigen::Matrix3d R;
  constexpr double pi = std::numbers::pi;
  if (up == Eigen::Vector3d::UnitZ()) {
    R.setIdentity();
  } else if (up == -Eigen::Vector3d::UnitZ()) {
    R = Eigen::AngleAxisd(pi, Eigen::Vector3d::UnitX()).toRotationMatrix();
  } else if (up.cwiseAbs() == Eigen::Vector3d::UnitY()) {
    // About x by +90 degrees takes +y to +z; by -90 degrees, -y.
    R = Eigen::AngleAxisd(up.y() > 0 ? pi / 2 : -pi / 2, Eigen::Vector3d::UnitX())
            .toRotationMatrix();
  } else if (up.cwiseAbs() == Eigen::Vector3d::UnitX()) {
    // About y by -90 degrees takes +x to +z; by +90 degrees, -x.
    R = Eigen::AngleAxisd(up.x() > 0 ? -pi / 2 : pi / 2, Eigen::Vector3d::UnitY())
            .toRotationMatrix();
  } else {
    throw std::invalid_argument("up must be one of the six axes");
  }
  // Exact signs (no 1e-17 from the angles' cosines).
  return R.array().round().matrix();
}

Mesh turnedUp(const Mesh& mesh, const Eigen::Vector3d& up) {
  const Eigen::Matrix3f Rf = upTurn(up).cast<float>();
  Mesh turned = mesh;
  for (Eigen::Vector3f& v : turned.vertices) v = Rf * v;
  for (Eigen::Vector3f& n : turned.normals) n = Rf * n;
  return turned;
}

std::vector<double> vertexHeights(const Mesh& mesh, const Eigen::Vector3d& up) {
  std::vector<double> heights;
  heights.reserve(mesh.vertices.size());
  double lowest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3f& v : mesh.vertices) {
    heights.push_back(up.dot(v.cast<double>()));
    lowest = std::min(lowest, heights.back());
  }
  for (double& h : heights) h -= lowest;
  return heights;
}

}  // namespace cblox
