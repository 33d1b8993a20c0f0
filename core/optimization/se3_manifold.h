#pragma once

#include <array>

#include <ceres/manifold.h>
#include <Eigen/Core>

#include "core/geometry/se3.h"

namespace cblox {

/// Number of doubles of a pose parameter block.
inline constexpr int kPoseAmbientSize = 7;
/// Number of degrees of freedom of a pose (tangent size).
inline constexpr int kPoseTangentSize = 6;

/// Pose parameter block as the optimisers store it (Ceres' "ambient" space):
///   x = [qx, qy, qz, qw, tx, ty, tz]
/// the unit quaternion in Eigen's coeffs() order (x, y, z, w), then the translation in
/// metres. The optimisers store world-to-camera poses T_C_G in this layout.
using PoseParameters = std::array<double, kPoseAmbientSize>;

/// Packs T into the 7-double layout above. Thread-safe (pure).
PoseParameters toPoseParameters(const Transformationd& T);

/// Unpacks 7 doubles in the layout above (the quaternion is normalised). Thread-safe (pure).
Transformationd fromPoseParameters(const double* x);

/// Rotation part of the Minus Jacobian: d phi / d q (3 x 4, columns qx, qy, qz, qw) of
/// phi = log(R(q_y) * R(q)^-1) at q_y = q, for a unit quaternion q:
///   2 * [qw I + [q_v]x,  -q_v].
/// It annihilates the radial direction q, so it is also the exact derivative of functions
/// that normalise their quaternion. Thread-safe (pure).
Eigen::Matrix<double, 3, 4> rotationTangentFromQuaternionJacobian(const Eigen::Quaterniond& q);

/// ceres::Manifold for SE(3) poses in the 7-double layout above, with a LEFT perturbation:
///   Plus(T, delta)  = exp(delta) * T,
///   Minus(T_y, T_x) = log(T_y * T_x^-1),
/// where delta = [rho (metres); phi (radians, rotation vector)] is the tangent of
/// cblox::Transformationd::exp/log (translation first). For a pose T_C_G the perturbation
/// acts in the camera frame: p_C' = exp(delta) * p_C.
///
/// Jacobians (row-major, as Ceres expects) at delta = 0:
///   PlusJacobian (7 x 6):  d t / d rho = I, d t / d phi = -[t]x,
///                          d q_v / d phi = (qw I - [q_v]x) / 2, d qw / d phi = -q_v^T / 2;
///   MinusJacobian (6 x 7): d rho / d t = I, d rho / d q = [t]x * Jq, d phi / d q = Jq,
///                          Jq = rotationTangentFromQuaternionJacobian(q);
/// MinusJacobian * PlusJacobian = I.
///
/// Stateless: all member functions are thread-safe; one instance may be shared by many
/// parameter blocks and problems (pass Ownership::DO_NOT_TAKE_OWNERSHIP).
class SE3Manifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseAmbientSize; }
  int TangentSize() const override { return kPoseTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

}  // namespace cblox
