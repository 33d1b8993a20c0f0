#pragma once

#include <ceres/cost_function.h>
#include <Eigen/Core>

#include "core/geometry/se3.h"

namespace cblox {

/// Relative-pose error of a pose-graph edge between keyframes i and j with world-to-camera
/// poses T_Ci_G, T_Cj_G and the measured relative pose T_i_j = T_Ci_Cj (maps points of Cj
/// into Ci; the estimate is T_Ci_G * T_Cj_G^-1):
///   e = log(T_i_j^-1 * T_Ci_G * T_Cj_G^-1)  =  log(T_ij_measured^-1 * T_i^-1 * T_j)
/// with T_i = T_G_Ci, in the tangent [rho (m); phi (rad)] of Transformationd::log. Zero iff
/// the estimate equals the measurement. Thread-safe (pure).
Eigen::Matrix<double, 6, 1> relativePoseError(const Transformationd& T_i_j,
                                              const Transformationd& T_Ci_G,
                                              const Transformationd& T_Cj_G);

/// The upper-triangular U with U^T U = information (6 x 6, symmetric positive definite), so
/// that |U e|^2 = e^T information e. Throws std::invalid_argument if `information` is not
/// finite, symmetric (relative 1e-9) and positive definite. Thread-safe (pure).
Eigen::Matrix<double, 6, 6> sqrtInformation(const Eigen::Matrix<double, 6, 6>& information);

/// New Ceres cost with residual U * relativePoseError(T_i_j, T_Ci_G, T_Cj_G) over two pose
/// blocks T_Ci_G, T_Cj_G in the 7-double layout of se3_manifold.h (use SE3Manifold).
/// Automatic differentiation; the quaternions must be unit (SE3Manifold keeps them so).
/// The caller (usually a ceres::Problem) owns it. Thread-safe.
ceres::CostFunction* newRelativePoseCost(const Transformationd& T_i_j,
                                         const Eigen::Matrix<double, 6, 6>& sqrt_information);

}  // namespace cblox
