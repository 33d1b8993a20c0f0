#include "core/geometry/pinhole_camera.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cblox {
namespace {

std::string describe(const char* field, const char* requirement, double value) {
  std::ostringstream os;
  os << field << " must be " << requirement << ", got " << value;
  return os.str();
}

}  // namespace

std::string validate(const PinholeIntrinsics& in) {
  // Written as !(x > 0) so that NaN is rejected too.
  if (!(in.fx > 0) || !std::isfinite(in.fx)) return describe("fx", "> 0", in.fx);
  if (!(in.fy > 0) || !std::isfinite(in.fy)) return describe("fy", "> 0", in.fy);
  if (!std::isfinite(in.cx)) return describe("cx", "finite", in.cx);
  if (!std::isfinite(in.cy)) return describe("cy", "finite", in.cy);
  if (in.width <= 0) return describe("width", "> 0", in.width);
  if (in.height <= 0) return describe("height", "> 0", in.height);
  return {};
}

PinholeCamera::PinholeCamera(const PinholeIntrinsics& intrinsics) : intrinsics_(intrinsics) {
  const std::string error = validate(intrinsics);
  if (!error.empty()) throw std::invalid_argument("PinholeIntrinsics: " + error);
}

bool PinholeCamera::project(const Eigen::Vector3d& p_C, Eigen::Vector2d* uv) const {
  const double z = p_C.z();
  if (!(z > 0)) return false;
  const double u = intrinsics_.fx * p_C.x() / z + intrinsics_.cx;
  const double v = intrinsics_.fy * p_C.y() / z + intrinsics_.cy;
  // Negated comparisons so that NaN (and +-inf outside the image) are rejected.
  if (!(u >= 0 && u < intrinsics_.width && v >= 0 && v < intrinsics_.height)) return false;
  *uv = Eigen::Vector2d(u, v);
  return true;
}

bool PinholeCamera::projectToPixel(const Eigen::Vector3d& p_C, int* u, int* v) const {
  const double z = p_C.z();
  if (!(z > 0)) return false;
  const double uf = std::round(intrinsics_.fx * p_C.x() / z + intrinsics_.cx);
  const double vf = std::round(intrinsics_.fy * p_C.y() / z + intrinsics_.cy);
  if (!(uf >= 0 && uf < intrinsics_.width && vf >= 0 && vf < intrinsics_.height)) return false;
  *u = static_cast<int>(uf);
  *v = static_cast<int>(vf);
  return true;
}

Eigen::Vector3d PinholeCamera::backProject(const Eigen::Vector2d& uv, double depth) const {
  return Eigen::Vector3d((uv.x() - intrinsics_.cx) / intrinsics_.fx * depth,
                         (uv.y() - intrinsics_.cy) / intrinsics_.fy * depth, depth);
}

Eigen::Vector3d PinholeCamera::rayDirection(const Eigen::Vector2d& uv) const {
  return Eigen::Vector3d((uv.x() - intrinsics_.cx) / intrinsics_.fx,
                         (uv.y() - intrinsics_.cy) / intrinsics_.fy, 1.0);
}

PinholeIntrinsics PinholeCamera::fromK(const Eigen::Matrix3d& K, int width, int height) {
  const double tol = 1e-9 * std::max(1.0, std::abs(K(0, 0)));
  if (std::abs(K(0, 1)) > tol || std::abs(K(1, 0)) > tol) {
    throw std::invalid_argument("fromK: K must have zero skew (K(0,1) = K(1,0) = 0)");
  }
  if (std::abs(K(2, 0)) > tol || std::abs(K(2, 1)) > tol || std::abs(K(2, 2) - 1.0) > tol) {
    throw std::invalid_argument("fromK: K's bottom row must be (0, 0, 1)");
  }
  PinholeIntrinsics in;
  in.fx = K(0, 0);
  in.fy = K(1, 1);
  in.cx = K(0, 2);
  in.cy = K(1, 2);
  in.width = width;
  in.height = height;
  return in;
}

}  // namespace cblox
