#include "core/eval/trajectory_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <tuple>

#include <nlohmann/json.hpp>

namespace cblox {
namespace {

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

// Rotation angle of a unit quaternion in [0, pi] radians (accurate near 0 and pi).
double rotationAngle(const Eigen::Quaterniond& q) {
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

std::vector<AssociatedPose> associateNearest(const StampedTrajectory& ground_truth,
                                             const StampedTrajectory& estimate,
                                             const AssociationConfig& options) {
  struct Candidate {
    double difference;
    size_t estimate_index;
    size_t truth_index;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate[i].timestamp_s + options.time_offset_s;
    auto it = std::lower_bound(
        ground_truth.begin(), ground_truth.end(), t - options.max_difference_s,
        [](const StampedPose& pose, double time) { return pose.timestamp_s < time; });
    for (; it != ground_truth.end() && it->timestamp_s <= t + options.max_difference_s; ++it) {
      const double difference = std::abs(it->timestamp_s - t);
      if (difference <= options.max_difference_s) {
        candidates.push_back({difference, i, static_cast<size_t>(it - ground_truth.begin())});
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.difference, a.estimate_index, a.truth_index) <
           std::tie(b.difference, b.estimate_index, b.truth_index);
  });
  std::vector<bool> estimate_used(estimate.size(), false);
  std::vector<bool> truth_used(ground_truth.size(), false);
  std::vector<std::pair<size_t, size_t>> matches;
  for (const Candidate& c : candidates) {
    if (estimate_used[c.estimate_index] || truth_used[c.truth_index]) continue;
    estimate_used[c.estimate_index] = true;
    truth_used[c.truth_index] = true;
    matches.emplace_back(c.estimate_index, c.truth_index);
  }
  std::sort(matches.begin(), matches.end());
  std::vector<AssociatedPose> pairs;
  pairs.reserve(matches.size());
  for (const auto& [i, j] : matches) {
    pairs.push_back({estimate[i].timestamp_s, ground_truth[j].T_G_C, estimate[i].T_G_C});
  }
  return pairs;
}

std::vector<AssociatedPose> associateInterpolated(const StampedTrajectory& ground_truth,
                                                  const StampedTrajectory& estimate,
                                                  const AssociationConfig& options) {
  std::vector<AssociatedPose> pairs;
  for (const StampedPose& pose : estimate) {
    const std::optional<Transformationd> truth =
        interpolatePose(ground_truth, pose.timestamp_s + options.time_offset_s,
                        options.max_difference_s, options.max_difference_s);
    if (truth.has_value()) pairs.push_back({pose.timestamp_s, *truth, pose.T_G_C});
  }
  return pairs;
}

}  // namespace

const char* associationMethodName(AssociationMethod method) {
  switch (method) {
    case AssociationMethod::kNearest:
      return "nearest";
    case AssociationMethod::kInterpolate:
      return "interpolate";
  }
  return "unknown";
}

std::string AssociationConfig::validate() const {
  if (!(max_difference_s >= 0.0) || !std::isfinite(max_difference_s)) {
    return "association.max_difference_s must be finite and >= 0, got " +
           std::to_string(max_difference_s);
  }
  if (!std::isfinite(time_offset_s)) {
    return "association.time_offset_s must be finite, got " + std::to_string(time_offset_s);
  }
  return "";
}

std::vector<AssociatedPose> associateTrajectories(const StampedTrajectory& ground_truth,
                                                  const StampedTrajectory& estimate,
                                                  const AssociationConfig& options) {
  if (!options.validate().empty()) return {};
  switch (options.method) {
    case AssociationMethod::kNearest:
      return associateNearest(ground_truth, estimate, options);
    case AssociationMethod::kInterpolate:
      return associateInterpolated(ground_truth, estimate, options);
  }
  return {};
}

ErrorStatistics computeErrorStatistics(std::vector<double> errors) {
  ErrorStatistics stats;
  stats.count = errors.size();
  if (errors.empty()) return stats;
  const double n = static_cast<double>(errors.size());
  double sum = 0.0;
  double sum_squares = 0.0;
  for (const double e : errors) {
    sum += e;
    sum_squares += e * e;
  }
  stats.mean = sum / n;
  stats.rmse = std::sqrt(sum_squares / n);
  double deviation = 0.0;
  for (const double e : errors) deviation += (e - stats.mean) * (e - stats.mean);
  stats.stddev = std::sqrt(deviation / n);
  std::sort(errors.begin(), errors.end());
  stats.min = errors.front();
  stats.max = errors.back();
  const size_t middle = errors.size() / 2;
  stats.median =
      errors.size() % 2 == 1 ? errors[middle] : 0.5 * (errors[middle - 1] + errors[middle]);
  const double h = 0.9 * static_cast<double>(errors.size() - 1);
  const size_t below = std::min(static_cast<size_t>(h), errors.size() - 1);
  const size_t above = std::min(below + 1, errors.size() - 1);
  stats.p90 = errors[below] + (h - static_cast<double>(below)) * (errors[above] - errors[below]);
  return stats;
}

std::optional<AteResult> computeAte(const std::vector<AssociatedPose>& pairs,
                                    AlignmentType alignment_type, std::string* error) {
  if (pairs.empty()) {
    setError(error, "ATE: no associated pose pair");
    return std::nullopt;
  }
  std::vector<Eigen::Vector3d> estimated;
  std::vector<Eigen::Vector3d> truth;
  estimated.reserve(pairs.size());
  truth.reserve(pairs.size());
  for (const AssociatedPose& pair : pairs) {
    estimated.push_back(pair.T_E_C_estimate.translation());
    truth.push_back(pair.T_G_C_truth.translation());
  }
  std::string align_error;
  const std::optional<Alignment> alignment =
      umeyamaAlign(estimated, truth, alignment_type, &align_error);
  if (!alignment.has_value()) {
    setError(error, "ATE: " + align_error);
    return std::nullopt;
  }
  AteResult result;
  result.alignment_type = alignment_type;
  result.alignment = *alignment;
  result.errors_m.reserve(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    result.errors_m.push_back((truth[i] - alignment->apply(estimated[i])).norm());
  }
  result.translation_m = computeErrorStatistics(result.errors_m);
  return result;
}

std::string RpeConfig::validate() const {
  if (!(delta > 0.0) || !std::isfinite(delta)) {
    return "rpe.delta must be finite and > 0, got " + std::to_string(delta);
  }
  if (unit == RpeDeltaUnit::kFrames && delta != std::round(delta)) {
    return "rpe.delta must be a whole number of frames, got " + std::to_string(delta);
  }
  if (!(estimate_scale > 0.0) || !std::isfinite(estimate_scale)) {
    return "rpe.estimate_scale must be finite and > 0, got " + std::to_string(estimate_scale);
  }
  return "";
}

std::optional<RpeResult> computeRpe(const std::vector<AssociatedPose>& pairs,
                                    const RpeConfig& options, std::string* error) {
  if (const std::string message = options.validate(); !message.empty()) {
    setError(error, "RPE: " + message);
    return std::nullopt;
  }
  std::vector<double> translation_errors;
  std::vector<double> rotation_errors;
  const auto add = [&](const AssociatedPose& a, const AssociatedPose& b) {
    const Transformationd truth = a.T_G_C_truth.inverse() * b.T_G_C_truth;
    const Transformationd relative = a.T_E_C_estimate.inverse() * b.T_E_C_estimate;
    const Transformationd estimate(relative.rotation(),
                                   options.estimate_scale * relative.translation());
    const Transformationd E = truth.inverse() * estimate;
    translation_errors.push_back(E.translation().norm());
    rotation_errors.push_back(rotationAngle(E.rotation()) * 180.0 / std::numbers::pi);
  };
  if (options.unit == RpeDeltaUnit::kFrames) {
    const size_t step = static_cast<size_t>(options.delta);
    for (size_t i = 0; i + step < pairs.size(); ++i) add(pairs[i], pairs[i + step]);
  } else {
    for (size_t i = 0; i < pairs.size(); ++i) {
      const double target = pairs[i].timestamp_s + options.delta - 1e-9;
      const auto j = std::lower_bound(
          pairs.begin() + static_cast<std::ptrdiff_t>(i) + 1, pairs.end(), target,
          [](const AssociatedPose& pose, double time) { return pose.timestamp_s < time; });
      if (j == pairs.end()) break;  // later i have no partner either
      add(pairs[i], *j);
    }
  }
  if (translation_errors.empty()) {
    char delta[32];
    std::snprintf(delta, sizeof(delta), "%g", options.delta);
    setError(error, "RPE: no pose pair is " + std::string(delta) +
                        (options.unit == RpeDeltaUnit::kFrames ? " frames" : " s") + " apart (" +
                        std::to_string(pairs.size()) + " associated poses)");
    return std::nullopt;
  }
  RpeResult result;
  result.options = options;
  result.translation_m = computeErrorStatistics(std::move(translation_errors));
  result.rotation_deg = computeErrorStatistics(std::move(rotation_errors));
  return result;
}

std::string TrajectoryEvaluationConfig::validate() const {
  if (std::string message = association.validate(); !message.empty()) return message;
  if (std::string message = rpe.validate(); !message.empty()) return message;
  return "";
}

nlohmann::ordered_json TrajectoryEvaluation::toJson() const {
  const Eigen::Quaterniond& q = ate.alignment.T_A_B.rotation();
  const Eigen::Vector3d& t = ate.alignment.T_A_B.translation();
  nlohmann::ordered_json root;
  root["ground_truth_poses"] = ground_truth_poses;
  root["estimate_poses"] = estimate_poses;
  root["matched_poses"] = matched_poses;
  root["association"] = {{"method", associationMethodName(association.method)},
                         {"max_difference_s", association.max_difference_s},
                         {"time_offset_s", association.time_offset_s}};
  root["ate"] = {{"alignment", alignmentTypeName(ate.alignment_type)},
                 {"scale", ate.alignment.scale},
                 {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}},
                 {"translation_m", {t.x(), t.y(), t.z()}},
                 {"pairs", ate.translation_m.count},
                 {"rmse_m", ate.translation_m.rmse},
                 {"mean_m", ate.translation_m.mean},
                 {"median_m", ate.translation_m.median},
                 {"std_m", ate.translation_m.stddev},
                 {"min_m", ate.translation_m.min},
                 {"max_m", ate.translation_m.max}};
  nlohmann::ordered_json& r = root["rpe"];
  r["delta"] = rpe.options.delta;
  r["delta_unit"] = rpe.options.unit == RpeDeltaUnit::kFrames ? "frames" : "seconds";
  r["estimate_scale"] = rpe.options.estimate_scale;
  r["pairs"] = rpe.translation_m.count;
  const auto stats = [&r](const std::string& prefix, const std::string& unit,
                          const ErrorStatistics& s) {
    r[prefix + "_rmse_" + unit] = s.rmse;
    r[prefix + "_mean_" + unit] = s.mean;
    r[prefix + "_median_" + unit] = s.median;
    r[prefix + "_std_" + unit] = s.stddev;
    r[prefix + "_min_" + unit] = s.min;
    r[prefix + "_max_" + unit] = s.max;
  };
  stats("translation", "m", rpe.translation_m);
  stats("rotation", "deg", rpe.rotation_deg);
  return root;
}

std::optional<TrajectoryEvaluation> evaluateTrajectory(const StampedTrajectory& ground_truth,
                                                       const StampedTrajectory& estimate,
                                                       const TrajectoryEvaluationConfig& options,
                                                       std::string* error) {
  if (const std::string message = options.validate(); !message.empty()) {
    setError(error, "trajectory evaluation: " + message);
    return std::nullopt;
  }
  if (ground_truth.empty() || estimate.empty()) {
    setError(error, std::string("trajectory evaluation: the ") +
                        (ground_truth.empty() ? "ground truth" : "estimate") + " is empty");
    return std::nullopt;
  }
  TrajectoryEvaluation evaluation;
  evaluation.ground_truth_poses = ground_truth.size();
  evaluation.estimate_poses = estimate.size();
  evaluation.association = options.association;
  const std::vector<AssociatedPose> pairs =
      associateTrajectories(ground_truth, estimate, options.association);
  evaluation.matched_poses = pairs.size();
  if (pairs.empty()) {
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer),
                  "trajectory evaluation: no estimated pose matches the ground truth (%s, max "
                  "difference %g s, offset %g s; estimate %.6f..%.6f s, ground truth "
                  "%.6f..%.6f s)",
                  associationMethodName(options.association.method),
                  options.association.max_difference_s, options.association.time_offset_s,
                  estimate.front().timestamp_s, estimate.back().timestamp_s,
                  ground_truth.front().timestamp_s, ground_truth.back().timestamp_s);
    setError(error, buffer);
    return std::nullopt;
  }
  std::optional<AteResult> ate = computeAte(pairs, options.alignment, error);
  if (!ate.has_value()) return std::nullopt;
  evaluation.ate = std::move(*ate);
  RpeConfig rpe_options = options.rpe;
  if (options.alignment == AlignmentType::kSim3) {
    rpe_options.estimate_scale = evaluation.ate.alignment.scale;
  }
  std::optional<RpeResult> rpe = computeRpe(pairs, rpe_options, error);
  if (!rpe.has_value()) return std::nullopt;
  evaluation.rpe = std::move(*rpe);
  return evaluation;
}

StampedTrajectory applyAlignment(const StampedTrajectory& trajectory, const Alignment& alignment) {
  StampedTrajectory aligned;
  aligned.reserve(trajectory.size());
  for (const StampedPose& pose : trajectory) {
    aligned.push_back(
        {pose.timestamp_s, Transformationd(alignment.T_A_B.rotation() * pose.T_G_C.rotation(),
                                           alignment.apply(pose.T_G_C.translation()))});
  }
  return aligned;
}

}  // namespace cblox
