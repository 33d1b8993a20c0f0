#include "core/optimization/se3_manifold.h"

namespace cblox {

PoseParameters toPoseParameters(const Transformationd& T) {
  const Eigen::Quaterniond& q = T.rotation();
  const Eigen::Vector3d& t = T.translation();
  return {q.x(), q.y(), q.z(), q.w(), t.x(), t.y(), t.z()};
}

Transformationd fromPoseParameters(const double* x) {
  return Transformationd(Eigen::Quaterniond(x[3], x[0], x[1], x[2]),
                         Eigen::Vector3d(x[4], x[5], x[6]));
}

Eigen::Matrix<double, 3, 4> rotationTangentFromQuaternionJacobian(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 3, 4> J;
  J.leftCols<3>() = 2.0 * (q.w() * Eigen::Matrix3d::Identity() + skew<double>(q.vec()));
  J.col(3) = -2.0 * q.vec();
  return J;
}

bool SE3Manifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Transformationd T =
      Transformationd::exp(Eigen::Map<const Eigen::Matrix<double, 6, 1>>(delta)) *
      fromPoseParameters(x);
  const PoseParameters p = toPoseParameters(T);
  std::copy(p.begin(), p.end(), x_plus_delta);
  return true;
}

bool SE3Manifold::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> J(jacobian);
  const Eigen::Vector3d q_v(x[0], x[1], x[2]);
  const double q_w = x[3];
  const Eigen::Vector3d t(x[4], x[5], x[6]);
  J.setZero();
  J.block<3, 3>(0, 3) = 0.5 * (q_w * Eigen::Matrix3d::Identity() - skew<double>(q_v));
  J.block<1, 3>(3, 3) = -0.5 * q_v.transpose();
  J.block<3, 3>(4, 0).setIdentity();
  J.block<3, 3>(4, 3) = -skew<double>(t);
  return true;
}

bool SE3Manifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<Eigen::Matrix<double, 6, 1>> xi(y_minus_x);
  xi = (fromPoseParameters(y) * fromPoseParameters(x).inverse()).log();
  return true;
}

bool SE3Manifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobian);
  const Eigen::Quaterniond q(x[3], x[0], x[1], x[2]);
  const Eigen::Vector3d t(x[4], x[5], x[6]);
  const Eigen::Matrix<double, 3, 4> Jq = rotationTangentFromQuaternionJacobian(q);
  J.setZero();
  J.block<3, 4>(0, 0) = skew<double>(t) * Jq;
  J.block<3, 3>(0, 4).setIdentity();
  J.block<3, 4>(3, 0) = Jq;
  return true;
}

}  // namespace cblox
