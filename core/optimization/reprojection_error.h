#pragma once

#include <cmath>
#include <string>

#include <ceres/sized_cost_function.h>
#include <Eigen/Core>

#include "core/optimization/stereo_camera_model.h"

namespace cblox {

/// ORB-SLAM2's outlier thresholds: the 95% quantiles of chi-square with 2 dof (mono
/// observation) and 3 dof (stereo observation), applied to chi2 = inv_sigma2 * |e|^2.
inline constexpr double kChi2Mono95 = 5.991;
inline constexpr double kChi2Stereo95 = 7.815;

/// Points with depth z <= this (metres) in a camera are "behind" it: they cannot be
/// projected and count as outliers.
inline constexpr double kMinDepthM = 1e-6;

/// One keypoint measurement in the convention of StereoCameraModel: (u, v) left image
/// pixels, u_right >= 0 right column (stereo) or < 0 (mono), inv_sigma2 > 0.
struct StereoMeasurement {
  double u = 0.0;
  double v = 0.0;
  double u_right = -1.0;
  double inv_sigma2 = 1.0;
  /// 3 residuals if stereo, else 2. Thread-safe.
  int dimension() const { return u_right >= 0.0 ? 3 : 2; }
};

/// Empty if the measurement is usable (finite u, v, u_right; finite inv_sigma2 > 0), else a
/// message. Thread-safe (pure).
std::string validate(const StereoMeasurement& measurement);

/// Weighted reprojection residual of a measurement for a point p_C in the camera frame:
///   r = sqrt(inv_sigma2) * (measured - projected),  rows (u, v[, u_right]),
/// so that |r|^2 = chi2. Writes r (m.dimension() values) and, if dr_dp is non-null, the
/// row-major m.dimension() x 3 derivative d r / d p_C. Returns false (writing nothing) if
/// p_C.z() <= kMinDepthM. Thread-safe (pure); inline because it is the inner loop of
/// every optimiser here.
inline bool weightedReprojectionResidual(const StereoCameraModel& cam, const StereoMeasurement& m,
                                         const Eigen::Vector3d& p_C, double* r, double* dr_dp) {
  const double z = p_C.z();
  if (!(z > kMinDepthM)) return false;
  const double s = std::sqrt(m.inv_sigma2);
  const double z_inv = 1.0 / z;
  const double x_z = p_C.x() * z_inv;
  const double y_z = p_C.y() * z_inv;
  const double u = cam.fx * x_z + cam.cx;
  r[0] = s * (m.u - u);
  r[1] = s * (m.v - (cam.fy * y_z + cam.cy));
  const bool stereo = m.u_right >= 0.0;
  if (stereo) r[2] = s * (m.u_right - (u - cam.bf * z_inv));
  if (dr_dp != nullptr) {
    // d projected / d p_C, negated and scaled.
    const double a = -s * z_inv;
    dr_dp[0] = a * cam.fx;
    dr_dp[1] = 0.0;
    dr_dp[2] = -a * cam.fx * x_z;
    dr_dp[3] = 0.0;
    dr_dp[4] = a * cam.fy;
    dr_dp[5] = -a * cam.fy * y_z;
    if (stereo) {
      dr_dp[6] = dr_dp[0];
      dr_dp[7] = 0.0;
      dr_dp[8] = dr_dp[2] + a * cam.bf * z_inv;
    }
  }
  return true;
}

/// chi2 = |r|^2 of a measurement for p_C, or +infinity if the point is behind the camera
/// (z <= kMinDepthM). Thread-safe (pure).
inline double reprojectionChi2(const StereoCameraModel& cam, const StereoMeasurement& m,
                               const Eigen::Vector3d& p_C) {
  double r[3];
  if (!weightedReprojectionResidual(cam, m, p_C, r, nullptr)) return HUGE_VAL;
  const double e = r[0] * r[0] + r[1] * r[1];
  return m.u_right >= 0.0 ? e + r[2] * r[2] : e;
}

/// Ceres cost of one observation of a landmark p_G (3 doubles, metres) from a keyframe with
/// pose T_C_G (7 doubles, layout of se3_manifold.h): the residual of
/// weightedReprojectionResidual() at p_C = T_C_G * p_G (kResiduals = 3 stereo, 2 mono).
/// Analytic Jacobians: the tangent Jacobian d r / d delta = dr_dp * [I, -[p_C]x] (left
/// perturbation of SE3Manifold) is mapped to the ambient 7 columns by MinusJacobian, so that
/// ambient Jacobian * SE3Manifold::PlusJacobian equals the tangent Jacobian; the quaternion
/// is normalised before use, so the ambient Jacobian is exact too. Evaluate returns false if
/// the point is behind the camera (Ceres then rejects the step).
/// Immutable after construction; Evaluate is thread-safe.
template <int kResiduals>
class ReprojectionCost final : public ceres::SizedCostFunction<kResiduals, 7, 3> {
  static_assert(kResiduals == 2 || kResiduals == 3);

 public:
  ReprojectionCost(const StereoCameraModel& camera, const StereoMeasurement& measurement)
      : camera_(camera), measurement_(measurement) {}
  bool Evaluate(const double* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  StereoCameraModel camera_;
  StereoMeasurement measurement_;
};

/// New cost for a measurement: ReprojectionCost<3> if stereo, <2> if mono. The caller
/// (usually a ceres::Problem) owns it. Thread-safe.
ceres::CostFunction* newReprojectionCost(const StereoCameraModel& camera,
                                         const StereoMeasurement& measurement);

}  // namespace cblox
