#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "core/optimization/bundle_adjustment.h"

namespace cblox {

/// The Jacobian of a bundle-adjustment problem at a given state (normally the BA solution),
/// for covariance extraction (core/covariance, issue 6).
///
/// Included: every observation that is not flagged an outlier and whose point is in front of
/// its camera at the state. Unknowns (columns): the free (not fixed) keyframes with at least
/// one included observation, then the landmarks with at least one included observation,
/// each in input order. Fixed keyframes have no columns, which fixes the gauge; their
/// observations still contribute rows (they constrain the landmarks).
///
/// Column layout (K = keyframe_ids.size(), L = landmark_ids.size()):
///   columns [6k, 6k + 6)          keyframe k: the tangent delta = [rho (m); phi (rad)] of the
///                                 left perturbation T_C_G <- exp(delta) * T_C_G (SE3Manifold);
///   columns [6K + 3l, 6K + 3l + 3) landmark l: p_G (metres, world frame).
/// Row layout: the included observations in input order, 3 rows (u, v, u_right) for stereo and
/// 2 (u, v) for mono; observation_rows[i] is the first row of observation i or -1.
/// Rows are WEIGHTED residuals r = sqrt(inv_sigma2) * (measured - projected) (pixels scaled
/// to unit information), so J^T J is the Gauss-Newton information matrix with the
/// observations' information inv_sigma2 * I. The robust loss is NOT applied by default
/// (ORB-SLAM2's last local-BA pass has no robust kernel, and the covariance of the
/// inlier-only problem is wanted); with apply_robust_loss the rows are reweighted exactly as
/// ceres::Problem::Evaluate does for the Huber loss (Ceres' Corrector: both r and J scaled by
/// sqrt(rho'(chi2)) = sqrt(delta / sqrt(chi2)) when chi2 > delta^2, because rho'' <= 0).
struct BaLinearization {
  /// rows x (6K + 3L), row-major, compressed.
  Eigen::SparseMatrix<double, Eigen::RowMajor> jacobian;
  /// The (weighted, optionally robustified) residual vector, one entry per row.
  Eigen::VectorXd residuals;
  /// Column blocks: caller ids and input indices of the free keyframes, then the landmarks.
  std::vector<std::uint64_t> keyframe_ids;
  std::vector<int> keyframe_indices;
  std::vector<std::uint64_t> landmark_ids;
  std::vector<int> landmark_indices;
  /// Per input observation: its first row, or -1 if excluded.
  std::vector<int> observation_rows;

  /// 6 * number of keyframe column blocks. Thread-safe.
  int numPoseColumns() const { return 6 * static_cast<int>(keyframe_ids.size()); }
  /// First column of keyframe block k. Thread-safe.
  int keyframeColumn(int k) const { return 6 * k; }
  /// First column of landmark block l. Thread-safe.
  int landmarkColumn(int l) const { return numPoseColumns() + 3 * l; }
};

struct BaLinearizationConfig {
  /// Apply the Huber loss' reweighting to the rows (see BaLinearization). Default false.
  bool apply_robust_loss = false;
  /// Huber deltas on sqrt(chi2), used only with apply_robust_loss (defaults as in BA). > 0.
  double huber_delta_mono = std::sqrt(kChi2Mono95);
  double huber_delta_stereo = std::sqrt(kChi2Stereo95);
};

/// Empty if valid, else a message naming the first bad field. Thread-safe (pure).
std::string validate(const BaLinearizationConfig& config);

/// Linearises `problem` at its own keyframe poses and landmark positions. `outlier` is
/// empty (no outliers) or has one flag per observation (BundleAdjustmentResult::outlier).
/// Throws std::invalid_argument if the problem or the config is invalid (see validate()),
/// `outlier` has the wrong size, or no observation remains. Thread-safe (pure).
BaLinearization linearizeBundleAdjustment(const BundleAdjustmentProblem& problem,
                                          std::span<const std::uint8_t> outlier,
                                          const BaLinearizationConfig& config = {});

/// Linearises at the solution of bundleAdjust(problem, ...): the poses, points and outlier
/// flags of `result` replace those of `problem`. Throws std::invalid_argument as above or if
/// `result` does not match `problem` in size. Thread-safe (pure).
BaLinearization linearizeBundleAdjustmentSolution(const BundleAdjustmentProblem& problem,
                                                  const BundleAdjustmentResult& result,
                                                  const BaLinearizationConfig& config = {});

/// The information matrix H = J^T J (Gauss-Newton approximation of the Hessian of
/// 1/2 |r|^2), in the column layout of the linearization: square, symmetric with both
/// triangles stored, column-major, compressed. Its landmark block H_ll is block diagonal
/// (3 x 3 per landmark), so the reduced camera matrix S = H_pp - H_pl H_ll^-1 H_lp (6 x 6
/// blocks, one per keyframe column block; gauge fixed by the fixed keyframes) is cheap to
/// form; S^-1 is the covariance of the keyframe tangents [rho (m); phi (rad)]. Positive definite iff J has full column rank
/// (e.g. gauge fixed by at least one fixed keyframe, every landmark constrained in 3D).
/// Thread-safe (pure).
Eigen::SparseMatrix<double> informationMatrix(const BaLinearization& linearization);

}  // namespace cblox
