#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include <ceres/loss_function.h>
#include <Eigen/Core>

#include "core/optimization/se3_manifold.h"

namespace cblox {

struct BundleAdjustmentProblem;

/// How schurLevenbergMarquardt stores and solves the reduced camera matrix
/// (reduced_camera_system.h).
enum class ReducedMatrix {
  kDense,   ///< dense, Eigen's LLT: local windows (tens of free keyframes)
  kSparse,  ///< block-sparse, CHOLMOD with AMD: whole maps (hundreds and more)
};

/// Settings of one pass of schurLevenbergMarquardt (bundle_adjustment.h sets them from
/// BundleAdjustmentConfig).
struct SchurLmOptions {
  ReducedMatrix reduced_matrix = ReducedMatrix::kDense;
  int max_iterations = 10;    ///< steps (successful + unsuccessful), >= 1
  double time_limit_s = 0.0;  ///< checked before each step; 0 = none
  /// Robust losses on chi2 of mono / stereo observations (not owned); nullptr: none.
  const ceres::LossFunction* loss_mono = nullptr;
  const ceres::LossFunction* loss_stereo = nullptr;
  double function_tolerance = 1e-6;   ///< |cost change| <= this * cost: converged
  double gradient_tolerance = 1e-10;  ///< max |gradient| <= this: converged
  double parameter_tolerance = 1e-8;  ///< |step| <= this * (|x| + this): converged
  const std::atomic<bool>* abort = nullptr;  ///< polled before each step
};

struct SchurLmSummary {
  bool solved = false;  ///< false if no observation was active (nothing was changed)
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int successful_steps = 0;
  int unsuccessful_steps = 0;
  bool aborted = false;  ///< `abort` was seen raised
};

/// One pass of bundle adjustment by our own Levenberg-Marquardt with an explicit Schur
/// complement, without Ceres (g2o's scheme for ORB-SLAM2's local BA). It minimises the cost
/// Ceres minimises for the same pass in bundle_adjustment.cc: 1/2 sum rho(chi2) over the
/// observations with active[i] != 0 (rho: the options' loss functions, else identity), over the
/// poses of the keyframes that are not fixed (left perturbation, tangent [rho; phi] as
/// SE3Manifold) and the positions of the landmarks those observations see.
///
/// Each step linearizes every active observation (Jacobians of reprojection_error.h), weighs
/// it by rho'(chi2) (the IRLS weight: for a loss with rho'' <= 0 such as Huber, what Ceres'
/// residual correction amounts to), eliminates every landmark (3 x 3 blocks) into the reduced
/// camera matrix (6 x free keyframes wide; dense or block-sparse by options.reduced_matrix),
/// solves it by Cholesky (Eigen's LLT, or CHOLMOD with AMD and the symbolic factorisation
/// done once per pass) and back-substitutes the landmarks. Damping and the step control are
/// Ceres' Levenberg-Marquardt strategy with its defaults: the normal equations' diagonal,
/// clamped to [1e-6, 1e32], over a trust-region radius that starts at 1e4; a step is taken if
/// it achieves more than 1e-3 of the decrease the model predicts; a step that puts a point
/// behind a camera, or a reduced matrix that is not positive definite, is unsuccessful.
///
/// `poses` (T_C_G in the 7-double layout) and `points` (p_G) are read as the start and
/// written with the solution; fixed[k] keyframes and the landmarks of no active observation
/// are left exactly as given. Every active observation must have its point in front of its
/// camera at the start (bundleAdjust guarantees it). Single-threaded; thread-safe for
/// distinct outputs.
SchurLmSummary schurLevenbergMarquardt(const BundleAdjustmentProblem& problem,
                                       const std::vector<std::uint8_t>& active,
                                       const SchurLmOptions& options,
                                       std::vector<PoseParameters>* poses,
                                       std::vector<Eigen::Vector3d>* points);

}  // namespace cblox
