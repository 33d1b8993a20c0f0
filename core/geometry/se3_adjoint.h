#pragma once

#include <Eigen/Core>

#include "core/geometry/se3.h"

namespace cblox {

/// The adjoint of T for the tangent order of SE3::exp, xi = [rho; phi]:
///   T * exp(xi) * T^-1 == exp(adjoint(T) * xi),   adjoint(T) = [R, [t]x R; 0, R].
/// So a left perturbation exp(xi) P of a pose P is the left perturbation
/// exp(adjoint(T) * xi) of T P, and a covariance Sigma of xi becomes
/// adjoint(T) Sigma adjoint(T)^T for T P. Thread-safe (pure).
template <typename Scalar>
Eigen::Matrix<Scalar, 6, 6> adjoint(const SE3<Scalar>& T) {
  const Eigen::Matrix<Scalar, 3, 3> R = T.rotation().toRotationMatrix();
  Eigen::Matrix<Scalar, 6, 6> A = Eigen::Matrix<Scalar, 6, 6>::Zero();
  A.template topLeftCorner<3, 3>() = R;
  A.template topRightCorner<3, 3>() = skew(T.translation()) * R;
  A.template bottomRightCorner<3, 3>() = R;
  return A;
}

}  // namespace cblox
