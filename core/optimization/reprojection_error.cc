#include "core/optimization/reprojection_error.h"

#include "core/optimization/se3_manifold.h"

namespace cblox {

std::string validate(const StereoMeasurement& m) {
  if (!std::isfinite(m.u) || !std::isfinite(m.v) || !std::isfinite(m.u_right)) {
    return "u, v and u_right must be finite";
  }
  if (!(m.inv_sigma2 > 0) || !std::isfinite(m.inv_sigma2)) {
    return "inv_sigma2 must be > 0 and finite";
  }
  return {};
}

template <int kResiduals>
bool ReprojectionCost<kResiduals>::Evaluate(const double* const* parameters, double* residuals,
                                            double** jacobians) const {
  const double* x = parameters[0];
  const Eigen::Quaterniond q = Eigen::Quaterniond(x[3], x[0], x[1], x[2]).normalized();
  const Eigen::Matrix3d R = q.toRotationMatrix();
  const Eigen::Vector3d Rp = R * Eigen::Map<const Eigen::Vector3d>(parameters[1]);
  const Eigen::Vector3d p_C = Rp + Eigen::Vector3d(x[4], x[5], x[6]);
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> dr_dp;
  const bool need_jacobian =
      jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
  if (!weightedReprojectionResidual(camera_, measurement_, p_C, residuals,
                                    need_jacobian ? dr_dp.data() : nullptr)) {
    return false;
  }
  if (!need_jacobian) return true;
  const auto A = dr_dp.topRows<kResiduals>();
  if (jacobians[0] != nullptr) {
    // Tangent Jacobian A * [I, -[p_C]x] times MinusJacobian: the translation columns are A,
    // the quaternion columns A * ([t]x - [p_C]x) * Jq = -A * [R p_G]x * Jq.
    Eigen::Map<Eigen::Matrix<double, kResiduals, 7, Eigen::RowMajor>> J(jacobians[0]);
    J.template leftCols<4>() = -A * skew<double>(Rp) * rotationTangentFromQuaternionJacobian(q);
    J.template rightCols<3>() = A;
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kResiduals, 3, Eigen::RowMajor>> J(jacobians[1]);
    J = A * R;
  }
  return true;
}

template class ReprojectionCost<2>;
template class ReprojectionCost<3>;

ceres::CostFunction* newReprojectionCost(const StereoCameraModel& camera,
                                         const StereoMeasurement& measurement) {
  if (measurement.dimension() == 3) return new ReprojectionCost<3>(camera, measurement);
  return new ReprojectionCost<2>(camera, measurement);
}

}  // namespace cblox
