#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/eval/umeyama.h"
#include "core/geometry/se3.h"
#include "core/io/tum_trajectory.h"

namespace cblox {

/// How estimated poses are paired with ground-truth poses.
enum class AssociationMethod {
  /// TUM's associate.py: among all (estimate, ground truth) pairs whose time difference is
  /// <= max_difference_s, pairs are taken greedily by increasing difference, each ground-truth
  /// and each estimated pose at most once; so an estimate whose nearest ground-truth pose went
  /// to a closer estimate takes its next-nearest one. (associate.py rejects a difference equal
  /// to the maximum; here it is accepted.) Ground-truth poses are used as recorded.
  kNearest,
  /// The ground truth is interpolated (interpolatePose(), geodesic) at each estimated time
  /// stamp; the two ground-truth poses around it must be at most max_difference_s apart, and
  /// a time stamp up to max_difference_s outside the ground truth takes the end pose. Better
  /// for a high-rate ground truth (motion capture) against a lower-rate estimate.
  kInterpolate,
};

/// "nearest" or "interpolate". Thread-safe.
const char* associationMethodName(AssociationMethod method);

/// Options of associateTrajectories(). Plain value type.
struct AssociationConfig {
  AssociationMethod method = AssociationMethod::kNearest;
  /// kNearest: largest |t_gt - (t_est + time_offset_s)| accepted (inclusive), seconds.
  /// kInterpolate: largest gap between the two ground-truth poses interpolated, and the
  /// tolerance at either end. Must be >= 0 and finite. TUM's tools default to 0.02 s.
  double max_difference_s = 0.02;
  /// Added to the estimate's time stamps before association (seconds; TUM's --offset).
  double time_offset_s = 0.0;

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// One estimated pose paired with the ground truth at (about) the same time.
struct AssociatedPose {
  double timestamp_s = 0.0;        ///< the estimate's time stamp (before time_offset_s)
  Transformationd T_G_C_truth;     ///< ground-truth pose (nearest or interpolated)
  Transformationd T_E_C_estimate;  ///< estimated pose, in the estimate's own world frame E
};

/// Pairs `estimate` with `ground_truth` (both sorted by strictly increasing time, as
/// readTumTrajectory() returns them) as `options.method` describes. The result is sorted by
/// the estimate's time; its size is the number of matched poses (0 when nothing matches).
/// Invalid options give an empty result. kNearest takes O(c log c) for c candidate pairs
/// within max_difference_s, kInterpolate O(n log m). Thread-safe (pure).
std::vector<AssociatedPose> associateTrajectories(const StampedTrajectory& ground_truth,
                                                  const StampedTrajectory& estimate,
                                                  const AssociationConfig& options);

/// Summary of a set of non-negative errors. All zero when count == 0.
struct ErrorStatistics {
  size_t count = 0;
  double rmse = 0.0;  ///< sqrt(mean(e^2))
  double mean = 0.0;
  double median = 0.0;  ///< middle value; mean of the two middle values for an even count
  /// 90th percentile, linear between order statistics (numpy's default, R type 7): with the
  /// errors sorted e_0 <= ... <= e_(n-1) and h = 0.9 (n - 1), e_floor(h) + (h - floor(h)) *
  /// (e_(floor(h)+1) - e_floor(h)).
  double p90 = 0.0;
  double stddev = 0.0;  ///< population standard deviation sqrt(mean((e - mean)^2)), as TUM
  double min = 0.0;
  double max = 0.0;
};

/// Statistics of `errors` (any order). Thread-safe (pure).
ErrorStatistics computeErrorStatistics(std::vector<double> errors);

/// Absolute trajectory error (TUM's evaluate_ate): the estimated positions are aligned onto
/// the ground-truth positions with umeyamaAlign(points_B = estimated, points_A = truth), so
/// alignment.T_A_B is T_G_E; the error of pair i is
/// |p_truth_i - alignment.apply(p_estimate_i)| in metres.
struct AteResult {
  AlignmentType alignment_type = AlignmentType::kSE3;
  Alignment alignment;            ///< estimate frame E -> ground-truth frame G (T_G_E, scale)
  ErrorStatistics translation_m;  ///< count is the number of pairs
  std::vector<double> errors_m;   ///< per pair, in the order of the pairs
};

/// ATE of associated pairs. Returns std::nullopt with a message when there is no pair or the
/// alignment fails (see umeyamaAlign(): fewer than 3 pairs or collinear positions for kSE3 and
/// kSim3). Thread-safe (pure).
std::optional<AteResult> computeAte(const std::vector<AssociatedPose>& pairs,
                                    AlignmentType alignment_type, std::string* error);

/// Unit of the RPE delta.
enum class RpeDeltaUnit {
  kFrames,   ///< delta counts associated pairs: (i, i + delta)
  kSeconds,  ///< (i, j) with j the first pair whose time is >= t_i + delta - 1e-9 s
};

/// Options of computeRpe(). Plain value type.
struct RpeConfig {
  double delta = 1.0;  ///< > 0; a whole number for kFrames
  RpeDeltaUnit unit = RpeDeltaUnit::kFrames;
  /// Multiplies the estimate's relative translations (P_i^-1 P_j) before comparing; pass the
  /// Sim3 ATE scale to evaluate a monocular (scale-free) estimate. > 0, finite.
  double estimate_scale = 1.0;

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// Relative pose error (TUM's evaluate_rpe): for each pair (i, j) selected by the delta,
/// E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j) with Q the ground truth and P the estimate; the
/// translational error is |translation(E)| (metres) and the rotational error the rotation
/// angle of E (degrees, in [0, 180]). Independent of the estimate's world frame, so no
/// alignment is needed.
struct RpeResult {
  RpeConfig options;
  ErrorStatistics translation_m;
  ErrorStatistics rotation_deg;
};

/// RPE of associated pairs (sorted by time, as associateTrajectories() returns them). Returns
/// std::nullopt with a message for invalid options or when no pair (i, j) is delta apart.
/// Thread-safe (pure).
std::optional<RpeResult> computeRpe(const std::vector<AssociatedPose>& pairs,
                                    const RpeConfig& options, std::string* error);

/// Options of evaluateTrajectory(). Plain value type.
struct TrajectoryEvaluationConfig {
  AssociationConfig association;
  AlignmentType alignment = AlignmentType::kSE3;
  RpeConfig rpe;  ///< rpe.estimate_scale is replaced by the ATE scale for kSim3

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// Everything evaluateTrajectory() computes. Plain value type.
struct TrajectoryEvaluation {
  size_t ground_truth_poses = 0;
  size_t estimate_poses = 0;
  size_t matched_poses = 0;  ///< associated pairs
  AssociationConfig association;
  AteResult ate;
  RpeResult rpe;

  /// The result as a JSON object (keys in this order):
  ///   {"ground_truth_poses", "estimate_poses", "matched_poses",
  ///    "association": {"method", "max_difference_s", "time_offset_s"},
  ///    "ate": {"alignment", "scale", "rotation_xyzw": [4], "translation_m": [3], "pairs",
  ///            "rmse_m", "mean_m", "median_m", "std_m", "min_m", "max_m"},
  ///    "rpe": {"delta", "delta_unit" ("frames" or "seconds"), "estimate_scale", "pairs",
  ///            "translation_rmse_m", "translation_mean_m", "translation_median_m",
  ///            "translation_std_m", "translation_min_m", "translation_max_m",
  ///            "rotation_rmse_deg", "rotation_mean_deg", "rotation_median_deg",
  ///            "rotation_std_deg", "rotation_min_deg", "rotation_max_deg"}}
  /// Counts are unsigned integers; nlohmann's dump() writes doubles in the shortest form
  /// that reads back to the same double and non-finite ones as null. Per-pair errors are not
  /// included. Thread-safe.
  nlohmann::ordered_json toJson() const;
};

/// Associates, then computes the ATE and the RPE. Returns std::nullopt with a message
/// when the options are invalid, either trajectory is empty, no pose matches, or ATE or RPE
/// fails (see computeAte() and computeRpe()). Thread-safe (pure).
std::optional<TrajectoryEvaluation> evaluateTrajectory(const StampedTrajectory& ground_truth,
                                                       const StampedTrajectory& estimate,
                                                       const TrajectoryEvaluationConfig& options,
                                                       std::string* error);

/// `trajectory` mapped through `alignment` (e.g. AteResult::alignment, to draw the estimate
/// over the ground truth): position alignment.apply(t), rotation R_A_B * R; time stamps kept.
/// Thread-safe (pure).
StampedTrajectory applyAlignment(const StampedTrajectory& trajectory, const Alignment& alignment);

}  // namespace cblox
