#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/se3.h"
#include "core/optimization/reprojection_error.h"
#include "core/optimization/stereo_camera_model.h"

namespace cblox {

/// Motion-only pose optimisation (ORB-SLAM2's Optimizer::PoseOptimization) without Ceres: a
/// hand-written Levenberg-Marquardt on the 6 dof of T_C_G for the tracking thread.
///
/// Parametrisation: T_C_G (world-to-camera) with the left perturbation of SE3Manifold,
/// T <- exp(delta) * T, delta = [rho (m); phi (rad)].
///
/// Scheme: `rounds` rounds of at most `iterations_per_round` LM iterations. Each round
/// optimises over the observations that are inliers at its start (all at the first round),
/// with the Huber kernel in the first `robust_rounds` rounds and without it afterwards. After
/// every round ALL observations are classified at the current pose: outlier if chi2 >
/// chi2_stereo (stereo) / chi2_mono (mono) or the point is behind the camera; an outlier can
/// come back as an inlier in a later round. Unlike ORB-SLAM2 (which restarts every round
/// from the initial pose), each round continues from the previous round's pose.

/// One observation of a fixed landmark: its position p_G (metres, world frame) and the
/// measurement (u, v, u_right, inv_sigma2) in the convention of StereoCameraModel.
struct PoseObservation : StereoMeasurement {
  Eigen::Vector3d p_G = Eigen::Vector3d::Zero();
};

struct PoseOptimizerConfig {
  /// Rounds of optimisation + outlier classification (ORB-SLAM2: 4). >= 1.
  int rounds = 4;
  /// Maximum LM iterations per round (ORB-SLAM2: 10). >= 1.
  int iterations_per_round = 10;
  /// The Huber kernel is used in rounds [0, robust_rounds) (ORB-SLAM2 removes it after the
  /// third round: 3). 0 = never robust. In [0, rounds].
  int robust_rounds = 3;
  /// Outlier thresholds on chi2 (dimensionless; defaults: 95% chi-square quantiles).
  double chi2_mono = kChi2Mono95;
  double chi2_stereo = kChi2Stereo95;
  /// Huber deltas on sqrt(chi2) (defaults: square roots of the thresholds). > 0.
  double huber_delta_mono = std::sqrt(kChi2Mono95);
  double huber_delta_stereo = std::sqrt(kChi2Stereo95);
  /// Convergence: a step with |delta| below this (metres and radians in one Euclidean norm)
  /// is applied and ends the round. >= 0.
  double min_step_norm = 1e-8;
};

/// Empty if valid, else a message naming the first bad field. Thread-safe (pure).
std::string validate(const PoseOptimizerConfig& config);

struct PoseOptimizationResult {
  /// The optimised world-to-camera pose.
  Transformationd T_C_G;
  /// Per observation (input order): 1 if inlier after the last round's classification.
  std::vector<std::uint8_t> inlier;
  /// Number of 1s in `inlier`.
  int num_inliers = 0;
  /// LM iterations over all rounds (retries with more damping within one iteration do not
  /// count).
  int iterations = 0;
  /// Sum of chi2 over the final inliers at the initial and at the final pose
  /// (dimensionless; points behind the initial camera count as 0 there).
  double initial_chi2 = 0.0;
  double final_chi2 = 0.0;
};

/// Optimises T_C_G from `T_C_G_initial` against observations of fixed landmarks.
/// Throws std::invalid_argument with a clear message if the camera or the config is invalid,
/// `observations` is empty, or an observation has a non-finite value or inv_sigma2 <= 0.
/// With fewer than 3 inliers the pose is poorly constrained: LM's damping keeps it near the
/// start; check num_inliers. Thread-safe (no shared state); allocates only the result.
PoseOptimizationResult optimizePose(const StereoCameraModel& camera,
                                    const Transformationd& T_C_G_initial,
                                    std::span<const PoseObservation> observations,
                                    const PoseOptimizerConfig& config = {});

}  // namespace cblox
