#include "core/optimization/ba_linearization.h"

#include <stdexcept>

#include "core/optimization/reprojection_error.h"

namespace cblox {
namespace {

constexpr int kMaxNonZerosPerRow = 9;  // 6 pose + 3 point columns

// sqrt(rho'(chi2)) of Ceres' HuberLoss (the Corrector's scale when rho'' <= 0).
double huberRowScale(double chi2, double delta) {
  return chi2 > delta * delta ? std::sqrt(delta / std::sqrt(chi2)) : 1.0;
}

// The linearization at the poses pose_at(k) and points point_at(l) (the problem's own or
// a BA result's, without copying the problem).
template <typename PoseAt, typename PointAt>
BaLinearization linearize(const BundleAdjustmentProblem& problem, PoseAt pose_at, PointAt point_at,
                          std::span<const std::uint8_t> outlier,
                          const BaLinearizationConfig& config) {
  if (const std::string e = validate(problem); !e.empty()) {
    throw std::invalid_argument("linearizeBundleAdjustment: " + e);
  }
  const size_t n = problem.observations.size();
  if (!outlier.empty() && outlier.size() != n) {
    throw std::invalid_argument("linearizeBundleAdjustment: " + std::to_string(outlier.size()) +
                                " outlier flags for " + std::to_string(n) + " observations");
  }
  if (const std::string e = validate(config); !e.empty()) {
    throw std::invalid_argument("linearizeBundleAdjustment: config: " + e);
  }

  // Which observations, keyframes and landmarks take part; rows and columns.
  BaLinearization lin;
  lin.observation_rows.assign(n, -1);
  std::vector<Eigen::Vector3d> p_C(n);
  std::vector<int> keyframe_block(problem.keyframes.size(), -1);
  std::vector<int> landmark_block(problem.landmarks.size(), -1);
  int rows = 0;
  for (size_t i = 0; i < n; ++i) {
    const BaObservation& o = problem.observations[i];
    if (!outlier.empty() && outlier[i]) continue;
    p_C[i] = pose_at(o.keyframe) * point_at(o.landmark);
    if (!(p_C[i].z() > kMinDepthM)) continue;
    lin.observation_rows[i] = rows;
    rows += o.dimension();
    if (!problem.keyframes[o.keyframe].fixed) keyframe_block[o.keyframe] = 0;
    landmark_block[o.landmark] = 0;
  }
  if (rows == 0) {
    throw std::invalid_argument(
        "linearizeBundleAdjustment: no observation left (all outliers "
        "or behind their cameras)");
  }
  for (size_t k = 0; k < keyframe_block.size(); ++k) {
    if (keyframe_block[k] < 0) continue;
    keyframe_block[k] = static_cast<int>(lin.keyframe_ids.size());
    lin.keyframe_ids.push_back(problem.keyframes[k].id);
    lin.keyframe_indices.push_back(static_cast<int>(k));
  }
  for (size_t l = 0; l < landmark_block.size(); ++l) {
    if (landmark_block[l] < 0) continue;
    landmark_block[l] = static_cast<int>(lin.landmark_ids.size());
    lin.landmark_ids.push_back(problem.landmarks[l].id);
    lin.landmark_indices.push_back(static_cast<int>(l));
  }
  const int cols = lin.landmarkColumn(static_cast<int>(lin.landmark_ids.size()));

  // Rows in increasing column order: pose columns always precede landmark columns.
  lin.jacobian.resize(rows, cols);
  lin.jacobian.reserve(Eigen::VectorXi::Constant(rows, kMaxNonZerosPerRow));
  lin.residuals.resize(rows);
  for (size_t i = 0; i < n; ++i) {
    const int row = lin.observation_rows[i];
    if (row < 0) continue;
    const BaObservation& o = problem.observations[i];
    const int dim = o.dimension();
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> A;
    Eigen::Vector3d r;
    weightedReprojectionResidual(problem.camera, o, p_C[i], r.data(), A.data());
    if (config.apply_robust_loss) {
      const double s = huberRowScale(r.head(dim).squaredNorm(), dim == 3 ? config.huber_delta_stereo
                                                                         : config.huber_delta_mono);
      r *= s;
      A *= s;
    }
    Eigen::Matrix<double, 3, 6> J_pose;
    J_pose.leftCols<3>() = A;
    J_pose.rightCols<3>() = A * skew<double>(-p_C[i]);
    const Eigen::Matrix3d J_point = A * pose_at(o.keyframe).rotationMatrix();
    const int kb = keyframe_block[o.keyframe];
    const int pose_col = kb >= 0 ? lin.keyframeColumn(kb) : -1;
    const int point_col = lin.landmarkColumn(landmark_block[o.landmark]);
    for (int d = 0; d < dim; ++d) {
      lin.residuals[row + d] = r[d];
      if (pose_col >= 0) {
        for (int c = 0; c < 6; ++c) lin.jacobian.insert(row + d, pose_col + c) = J_pose(d, c);
      }
      for (int c = 0; c < 3; ++c) lin.jacobian.insert(row + d, point_col + c) = J_point(d, c);
    }
  }
  lin.jacobian.makeCompressed();
  return lin;
}

}  // namespace

std::string validate(const BaLinearizationConfig& c) {
  if (!(c.huber_delta_mono > 0) || !(c.huber_delta_stereo > 0) ||
      !std::isfinite(c.huber_delta_mono) || !std::isfinite(c.huber_delta_stereo)) {
    return "huber deltas must be > 0 and finite";
  }
  return {};
}

BaLinearization linearizeBundleAdjustment(const BundleAdjustmentProblem& problem,
                                          std::span<const std::uint8_t> outlier,
                                          const BaLinearizationConfig& config) {
  return linearize(
      problem, [&](int k) -> const Transformationd& { return problem.keyframes[k].T_C_G; },
      [&](int l) -> const Eigen::Vector3d& { return problem.landmarks[l].p_G; }, outlier, config);
}

BaLinearization linearizeBundleAdjustmentSolution(const BundleAdjustmentProblem& problem,
                                                  const BundleAdjustmentResult& result,
                                                  const BaLinearizationConfig& config) {
  if (result.T_C_G.size() != problem.keyframes.size() ||
      result.p_G.size() != problem.landmarks.size() ||
      result.outlier.size() != problem.observations.size()) {
    throw std::invalid_argument(
        "linearizeBundleAdjustmentSolution: the BA result does not match the problem's sizes");
  }
  return linearize(
      problem, [&](int k) -> const Transformationd& { return result.T_C_G[k]; },
      [&](int l) -> const Eigen::Vector3d& { return result.p_G[l]; }, result.outlier, config);
}

Eigen::SparseMatrix<double> informationMatrix(const BaLinearization& linearization) {
  const Eigen::SparseMatrix<double> J = linearization.jacobian;  // column-major copy
  Eigen::SparseMatrix<double> H = J.transpose() * J;
  H.makeCompressed();
  return H;
}

}  // namespace cblox
