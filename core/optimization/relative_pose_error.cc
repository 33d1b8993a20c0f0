#include "core/optimization/relative_pose_error.h"

#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>
#include <Eigen/Cholesky>

namespace cblox {
namespace {

// Below this rotation angle squared (rad^2) the coefficient of V^-1 uses its series.
constexpr double kSeriesAngle2 = 1e-4;

// rho = V(phi)^-1 t, V^-1 = I - 1/2 [phi]x + c [phi]x^2 with
// c = (1 - (th/2) cot(th/2)) / th^2 = 1/12 + th^2/720 + th^4/30240 + ...
// Written for Jets (ADL picks ceres:: functions) and doubles.
template <typename T>
Eigen::Matrix<T, 3, 1> inverseLeftJacobianTimes(const Eigen::Matrix<T, 3, 1>& phi,
                                                const Eigen::Matrix<T, 3, 1>& t) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta2 = phi.squaredNorm();
  T c;
  if (theta2 < T(kSeriesAngle2)) {
    c = T(1.0 / 12.0) + theta2 * (T(1.0 / 720.0) + theta2 * T(1.0 / 30240.0));
  } else {
    const T half = sqrt(theta2) / T(2.0);
    c = (T(1.0) - half * cos(half) / sin(half)) / theta2;
  }
  const Eigen::Matrix<T, 3, 1> phi_x_t = phi.cross(t);
  return t - T(0.5) * phi_x_t + c * phi.cross(phi_x_t);
}

struct RelativePoseFunctor {
  Eigen::Quaterniond q_meas_inv;
  Eigen::Vector3d t_meas_inv;
  Eigen::Matrix<double, 6, 6> sqrt_information;

  template <typename T>
  bool operator()(const T* x_i, const T* x_j, T* residual) const {
    using Quat = Eigen::Quaternion<T>;
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Quat q_i(x_i[3], x_i[0], x_i[1], x_i[2]);
    const Quat q_j(x_j[3], x_j[0], x_j[1], x_j[2]);
    const Vec3 t_i(x_i[4], x_i[5], x_i[6]);
    const Vec3 t_j(x_j[4], x_j[5], x_j[6]);
    // T_Ci_Cj = T_Ci_G * T_Cj_G^-1, then E = T_i_j^-1 * T_Ci_Cj.
    const Quat q_ij = q_i * q_j.conjugate();
    const Vec3 t_ij = t_i - (q_ij * t_j);
    const Quat q_m = q_meas_inv.cast<T>();
    const Quat q_e = q_m * q_ij;
    const Vec3 t_e = q_m * t_ij + t_meas_inv.cast<T>();
    const T q_wxyz[4] = {q_e.w(), q_e.x(), q_e.y(), q_e.z()};
    Vec3 phi;
    ceres::QuaternionToAngleAxis(q_wxyz, phi.data());
    Eigen::Matrix<T, 6, 1> e;
    e.template head<3>() = inverseLeftJacobianTimes<T>(phi, t_e);
    e.template tail<3>() = phi;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r = sqrt_information.cast<T>() * e;
    return true;
  }
};

}  // namespace

Eigen::Matrix<double, 6, 1> relativePoseError(const Transformationd& T_i_j,
                                              const Transformationd& T_Ci_G,
                                              const Transformationd& T_Cj_G) {
  return (T_i_j.inverse() * T_Ci_G * T_Cj_G.inverse()).log();
}

Eigen::Matrix<double, 6, 6> sqrtInformation(const Eigen::Matrix<double, 6, 6>& information) {
  if (!information.allFinite()) {
    throw std::invalid_argument("sqrtInformation: the information matrix is not finite");
  }
  if (!information.isApprox(information.transpose(), 1e-9)) {
    throw std::invalid_argument("sqrtInformation: the information matrix is not symmetric");
  }
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(information);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument("sqrtInformation: the information matrix is not positive definite");
  }
  return llt.matrixU();
}

ceres::CostFunction* newRelativePoseCost(const Transformationd& T_i_j,
                                         const Eigen::Matrix<double, 6, 6>& sqrt_information) {
  const Transformationd T_j_i = T_i_j.inverse();
  return new ceres::AutoDiffCostFunction<RelativePoseFunctor, 6, 7, 7>(
      new RelativePoseFunctor{T_j_i.rotation(), T_j_i.translation(), sqrt_information});
}

}  // namespace cblox
