#include "core/geometry/radtan_distortion.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <Eigen/LU>

namespace cblox {

std::string validate(const RadTanCoefficients& c) {
  const std::pair<const char*, double> fields[] = {
      {"k1", c.k1}, {"k2", c.k2}, {"p1", c.p1}, {"p2", c.p2}, {"k3", c.k3}};
  for (const auto& [name, value] : fields) {
    if (!std::isfinite(value)) {
      std::ostringstream os;
      os << name << " must be finite, got " << value;
      return os.str();
    }
  }
  return {};
}

RadTanDistortion::RadTanDistortion(RadTanCoefficients coefficients) : c_(coefficients) {
  const std::string error = validate(c_);
  if (!error.empty()) throw std::invalid_argument("RadTanCoefficients: " + error);
}

Eigen::Vector2d RadTanDistortion::distort(const Eigen::Vector2d& xn) const {
  const double x = xn.x();
  const double y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (c_.k1 + r2 * (c_.k2 + r2 * c_.k3));
  const double xy = x * y;
  return Eigen::Vector2d(x * radial + 2.0 * c_.p1 * xy + c_.p2 * (r2 + 2.0 * x * x),
                         y * radial + c_.p1 * (r2 + 2.0 * y * y) + 2.0 * c_.p2 * xy);
}

Eigen::Matrix2d RadTanDistortion::jacobian(const Eigen::Vector2d& xn) const {
  const double x = xn.x();
  const double y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (c_.k1 + r2 * (c_.k2 + r2 * c_.k3));
  // d radial / d r2
  const double d_radial = c_.k1 + r2 * (2.0 * c_.k2 + 3.0 * r2 * c_.k3);
  const double cross = 2.0 * x * y * d_radial + 2.0 * c_.p1 * x + 2.0 * c_.p2 * y;
  Eigen::Matrix2d J;
  J(0, 0) = radial + 2.0 * x * x * d_radial + 2.0 * c_.p1 * y + 6.0 * c_.p2 * x;
  J(0, 1) = cross;
  J(1, 0) = cross;
  J(1, 1) = radial + 2.0 * y * y * d_radial + 6.0 * c_.p1 * y + 2.0 * c_.p2 * x;
  return J;
}

bool RadTanDistortion::undistort(const Eigen::Vector2d& xd, Eigen::Vector2d* xn, int max_iterations,
                                 double tolerance) const {
  Eigen::Vector2d x = xd;
  for (int i = 0;; ++i) {
    const Eigen::Vector2d residual = distort(x) - xd;
    if (!residual.allFinite()) break;
    if (residual.norm() <= tolerance) {
      *xn = x;
      return true;
    }
    if (i >= max_iterations) break;
    const Eigen::Matrix2d J = jacobian(x);
    const double det = J.determinant();
    if (!(std::abs(det) > 1e-12)) break;  // singular (or NaN) Jacobian
    x -= J.inverse() * residual;
  }
  *xn = x;
  return false;
}

}  // namespace cblox
