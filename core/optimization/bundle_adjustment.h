#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/se3.h"
#include "core/optimization/ceres_solver_config.h"
#include "core/optimization/reprojection_error.h"
#include "core/optimization/stereo_camera_model.h"

namespace cblox {

/// Bundle adjustment (ORB-SLAM2's Optimizer::LocalBundleAdjustment and, with
/// globalBundleAdjustmentConfig(), GlobalBundleAdjustemnt), on plain structs. Each pass is
/// solved by our own Schur-complement Levenberg-Marquardt (schur_lm.h): with a dense reduced
/// camera matrix when it has at most native_max_free_keyframes free keyframes (kAuto) or
/// kNativeDenseSchur is asked for, with a sparse one (CHOLMOD) above that when native_sparse
/// is set or kNativeSparseSchur is asked for; by Ceres otherwise. All minimise the same cost
/// with the same step control.
///
/// Unknowns: keyframe poses T_C_G (world-to-camera, 7 doubles with SE3Manifold: left
/// perturbation, tangent [rho (m); phi (rad)]) and landmark positions p_G (metres). Residuals:
/// ReprojectionCost per observation (3 stereo / 2 mono, weighted by sqrt(inv_sigma2)), with
/// the Huber loss on chi2 (delta = huber_delta_*). Ceres' cost is 1/2 sum rho(chi2).
///
/// Scheme (ORB-SLAM2): pass 1 runs `first_pass_iterations` with the Huber loss; then every
/// observation with chi2 > chi2_stereo / chi2_mono or a point behind its camera is dropped
/// and pass 2 runs `second_pass_iterations` on the rest (without the robust loss unless
/// robust_loss_in_second_pass). Finally ALL observations are classified at the solution with
/// the same test; the flags are returned (the caller erases those observations from its map).
/// Observations whose point is behind the camera at the INITIAL state are excluded from both
/// passes (Ceres could not evaluate them).
///
/// Gauge: keyframes with fixed = true are held constant. Local BA: the window's keyframes are
/// free, the keyframes that observe window landmarks but are outside the window are fixed.
/// Global BA: call bundleAdjust with every keyframe free except the gauge keyframe (e.g. the
/// first keyframe, id 0, fixed = true) and globalBundleAdjustmentConfig(). With no fixed
/// keyframe the problem has a 6-dof gauge freedom (stereo fixes the scale): Ceres' LM still
/// converges, but linearizeBundleAdjustment() then yields a singular information matrix.
///
/// Linear solvers of Debian's Ceres 2.1 (libceres-dev 2.1.0+really2.1.0+dfsg-1, linked
/// statically through Ceres::ceres): built with SuiteSparse (CHOLMOD), CXSparse, Eigen
/// sparse and LAPACK, so DENSE_SCHUR, SPARSE_SCHUR (with SUITE_SPARSE) and ITERATIVE_SCHUR are
/// all available; CUDA and Accelerate are not. Its Schur eliminator is specialised for fixed
/// block sizes such as <2, 3, 6> (all-mono problems) but not <3, 3, 6>, so mixed stereo/mono
/// problems use the generic eliminator. kAuto picks DENSE_SCHUR for windows of up to
/// dense_schur_max_free_keyframes free keyframes (the reduced camera matrix is only
/// 6 * free keyframes wide and dense Cholesky on it beats CHOLMOD's overhead) and SPARSE_SCHUR
/// above; SPARSE_SCHUR falls back to DENSE_SCHUR in a Ceres build without sparse libraries.
/// Landmarks are eliminated first (explicit ordering).

struct BaKeyframe {
  std::uint64_t id = 0;   ///< caller's keyframe id (reported back, not interpreted)
  Transformationd T_C_G;  ///< initial world-to-camera pose
  bool fixed = false;     ///< held constant (gauge / keyframes outside the window)
};

struct BaLandmark {
  std::uint64_t id = 0;                           ///< caller's landmark id
  Eigen::Vector3d p_G = Eigen::Vector3d::Zero();  ///< initial position, metres
};

/// An observation of landmarks[landmark] by keyframes[keyframe] with the measurement
/// (u, v, u_right, inv_sigma2) in the convention of StereoCameraModel.
struct BaObservation : StereoMeasurement {
  int keyframe = 0;  ///< index into BundleAdjustmentProblem::keyframes
  int landmark = 0;  ///< index into BundleAdjustmentProblem::landmarks
};

struct BundleAdjustmentProblem {
  StereoCameraModel camera;
  std::vector<BaKeyframe> keyframes;
  std::vector<BaLandmark> landmarks;
  std::vector<BaObservation> observations;
};

/// Empty if the problem is usable, else a message naming the first problem: invalid camera,
/// no keyframes / landmarks / observations, an index out of range, a non-finite value, or
/// inv_sigma2 <= 0. Thread-safe (pure).
std::string validate(const BundleAdjustmentProblem& problem);

enum class BaLinearSolver {
  kAuto,            ///< kDenseSchur up to dense_schur_max_free_keyframes, else kSparseSchur
  kDenseSchur,      ///< ceres::DENSE_SCHUR
  kSparseSchur,     ///< ceres::SPARSE_SCHUR with SuiteSparse (Eigen sparse if absent)
  kIterativeSchur,  ///< ceres::ITERATIVE_SCHUR with the SCHUR_JACOBI preconditioner
  /// Our own Levenberg-Marquardt with a dense Schur complement, no Ceres (schur_lm.h): for
  /// windows of tens of free keyframes, not whole maps.
  kNativeDenseSchur,
  /// The same with a block-sparse reduced camera matrix factorised by CHOLMOD: whole maps.
  kNativeSparseSchur,
};

/// BundleAdjustmentResult::linear_solver of kNativeDenseSchur and kNativeSparseSchur.
inline constexpr const char* kNativeDenseSchurName = "NATIVE_DENSE_SCHUR";
inline constexpr const char* kNativeSparseSchurName = "NATIVE_SPARSE_SCHUR";

struct BundleAdjustmentConfig {
  /// Iterations of the robust pass (ORB-SLAM2 local BA: 5). >= 1.
  int first_pass_iterations = 5;
  /// Iterations after dropping outliers (ORB-SLAM2 local BA: 10). 0 = no second pass.
  int second_pass_iterations = 10;
  /// ORB-SLAM2 removes the robust kernel in the second pass (false).
  bool robust_loss_in_second_pass = false;
  /// Outlier thresholds on chi2 (dimensionless; defaults: 95% chi-square quantiles). > 0.
  double chi2_mono = kChi2Mono95;
  double chi2_stereo = kChi2Stereo95;
  /// Huber deltas on sqrt(chi2) (defaults: square roots of the thresholds). > 0.
  double huber_delta_mono = std::sqrt(kChi2Mono95);
  double huber_delta_stereo = std::sqrt(kChi2Stereo95);
  BaLinearSolver linear_solver = BaLinearSolver::kAuto;
  /// kAuto uses DENSE_SCHUR up to this many free keyframes, SPARSE_SCHUR above. >= 0.
  /// Measured (cblox-bench-optimization, ~4 observations per landmark): DENSE_SCHUR is
  /// faster at 10 and 60 free keyframes, SPARSE_SCHUR at 120 and 250.
  int dense_schur_max_free_keyframes = 80;
  /// kAuto uses kNativeDenseSchur for a pass with up to this many free keyframes (0: never).
  /// >= 0. Measured (cblox-bench-optimization, ~4 observations per landmark, CPU time): ours
  /// dense is 5-7x faster than DENSE_SCHUR at 10-60 free keyframes and 10 % faster than ours
  /// sparse at 60; at 120 ours sparse takes 71 ms, ours dense 182, SPARSE_SCHUR 244.
  int native_max_free_keyframes = 80;
  /// kAuto uses kNativeSparseSchur above native_max_free_keyframes (false: Ceres' Schur
  /// solvers as above). Measured (CPU time): 2-3x faster than SPARSE_SCHUR from 120 free
  /// keyframes to global BAs of 1000 (cblox-bench-optimization global_ba/loop: 2.8 s against
  /// 7.4 s); the town's live global BA 19.6 s against 27.1 s (BENCHMARKS.md).
  bool native_sparse = true;
  /// Threads, time limit (for both passes together) and tolerances of Ceres.
  CeresSolverConfig solver;
};

/// Preset for global BA after loop closure (ORB-SLAM2: 10 iterations with the Huber loss
/// and no outlier pass): first_pass_iterations = 10, second_pass_iterations = 0; outlier flags
/// are still computed at the end. Solver kAuto (ours with the sparse reduced matrix for
/// large maps).
/// Thread-safe (pure).
BundleAdjustmentConfig globalBundleAdjustmentConfig();

/// Empty if valid, else a message naming the first bad field. Thread-safe (pure).
std::string validate(const BundleAdjustmentConfig& config);

struct BundleAdjustmentResult {
  /// Optimised poses, one per input keyframe (fixed ones unchanged).
  std::vector<Transformationd> T_C_G;
  /// Optimised positions, one per input landmark, metres (landmarks without any usable
  /// observation are unchanged).
  std::vector<Eigen::Vector3d> p_G;
  /// Per observation (input order): 1 if an outlier at the solution (chi2 above threshold or
  /// point behind the camera).
  std::vector<std::uint8_t> outlier;
  int num_outliers = 0;
  /// Solver iterations (successful + unsuccessful steps) over both passes.
  int iterations = 0;
  /// Ceres cost (1/2 sum rho(chi2)) at the start of pass 1 and at the end of the last pass
  /// (of that pass' problem: without outliers and, by default, without the robust loss).
  double initial_cost = 0.0;
  double final_cost = 0.0;
  /// Sum of chi2 over the final inliers at the solution (no robust loss).
  double final_chi2 = 0.0;
  /// Wall-clock time of bundleAdjust, milliseconds.
  double time_ms = 0.0;
  /// The linear solver used (ceres::LinearSolverTypeToString, or kNativeDenseSchurName).
  std::string linear_solver;
  /// True if `abort` was raised (pass 2 is then skipped; the result is still usable).
  bool aborted = false;
  /// False if Ceres reported an unusable solution (then poses/points are the last usable
  /// ones and `message` says why).
  bool success = true;
  std::string message;
};

/// Runs the two-pass BA above. `abort` (optional) is polled after every Ceres iteration;
/// when it is true the current pass stops, keeping its latest iterate, and pass 2 is skipped
/// (ORB-SLAM2's mbAbortBA); the result is still usable.
/// Throws std::invalid_argument with validate()'s message if the problem or the config is
/// invalid. Thread-safe (no shared state); runs on the calling thread plus
/// config.solver.num_threads - 1 Ceres workers.
BundleAdjustmentResult bundleAdjust(const BundleAdjustmentProblem& problem,
                                    const BundleAdjustmentConfig& config = {},
                                    const std::atomic<bool>* abort = nullptr);

}  // namespace cblox
