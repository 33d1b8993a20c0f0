#include "core/optimization/disparity_offset.h"

#include <cmath>
#include <memory>
#include <vector>

#include <ceres/ceres.h>

#include "core/optimization/ceres_solver_config.h"
#include "core/optimization/reprojection_error.h"
#include "core/optimization/se3_manifold.h"

namespace cblox {
namespace {

// A stereo observation whose right column carries the offset c (parameter block 3, one
// double): the residual of ReprojectionCost<3> for the measurement with u_right - c, so
// r_right = sqrt(inv_sigma2) (u_right - c - (u - bf / z)) and d r_right / d c = -sqrt(inv_sigma2).
class OffsetStereoCost final : public ceres::SizedCostFunction<3, 7, 3, 1> {
 public:
  OffsetStereoCost(const StereoCameraModel& camera, const StereoMeasurement& measurement)
      : camera_(camera), measurement_(measurement) {}

  bool Evaluate(const double* const* parameters, double* residuals,
                double** jacobians) const override {
    StereoMeasurement shifted = measurement_;
    shifted.u_right -= parameters[2][0];
    const ReprojectionCost<3> cost(camera_, shifted);
    double* inner[2] = {jacobians != nullptr ? jacobians[0] : nullptr,
                        jacobians != nullptr ? jacobians[1] : nullptr};
    if (!cost.Evaluate(parameters, residuals, jacobians != nullptr ? inner : nullptr)) {
      return false;
    }
    if (jacobians != nullptr && jacobians[2] != nullptr) {
      jacobians[2][0] = 0.0;
      jacobians[2][1] = 0.0;
      jacobians[2][2] = -std::sqrt(measurement_.inv_sigma2);
    }
    return true;
  }

 private:
  StereoCameraModel camera_;
  StereoMeasurement measurement_;
};

DisparityOffsetEstimate failed(std::string reason) {
  DisparityOffsetEstimate e;
  e.reason = std::move(reason);
  return e;
}

}  // namespace

std::string DisparityOffsetSolverConfig::validate() const {
  if (iterations < 1) return "iterations must be >= 1, got " + std::to_string(iterations);
  if (min_stereo_observations < 1) {
    return "min_stereo_observations must be >= 1, got " + std::to_string(min_stereo_observations);
  }
  if (max_landmarks < 1) return "max_landmarks must be >= 1, got " + std::to_string(max_landmarks);
  return {};
}

DisparityOffsetEstimate estimateDisparityOffset(const BundleAdjustmentProblem& problem,
                                                const DisparityOffsetSolverConfig& config) {
  if (std::string e = config.validate(); !e.empty()) return failed("config: " + e);
  if (std::string e = validate(problem); !e.empty()) return failed("problem: " + e);
  bool any_fixed = false;
  for (const BaKeyframe& k : problem.keyframes) any_fixed = any_fixed || k.fixed;
  if (!any_fixed) return failed("no fixed keyframe (the gauge)");

  // The landmarks used: the first max_landmarks with a stereo observation.
  std::vector<std::uint8_t> use(problem.landmarks.size(), 0);
  int landmarks = 0;
  for (const BaObservation& o : problem.observations) {
    if (o.dimension() != 3 || use[static_cast<size_t>(o.landmark)]) continue;
    if (landmarks >= config.max_landmarks) continue;
    use[static_cast<size_t>(o.landmark)] = 1;
    ++landmarks;
  }
  std::vector<PoseParameters> poses;
  poses.reserve(problem.keyframes.size());
  for (const BaKeyframe& k : problem.keyframes) poses.push_back(toPoseParameters(k.T_C_G));
  std::vector<Eigen::Vector3d> points;
  points.reserve(problem.landmarks.size());
  for (const BaLandmark& l : problem.landmarks) points.push_back(l.p_G);
  double offset = 0.0;

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  ceres::HuberLoss huber_stereo(std::sqrt(kChi2Stereo95));
  ceres::HuberLoss huber_mono(std::sqrt(kChi2Mono95));
  SE3Manifold manifold;
  std::vector<std::uint8_t> pose_used(problem.keyframes.size(), 0);
  DisparityOffsetEstimate estimate;
  for (const BaObservation& o : problem.observations) {
    if (!use[static_cast<size_t>(o.landmark)]) continue;
    // Points behind a camera at the start cannot be evaluated: left out, as bundleAdjust does.
    const Eigen::Vector3d p_C = problem.keyframes[static_cast<size_t>(o.keyframe)].T_C_G *
                                problem.landmarks[static_cast<size_t>(o.landmark)].p_G;
    if (!(p_C.z() > kMinDepthM)) continue;
    double* pose = poses[static_cast<size_t>(o.keyframe)].data();
    double* point = points[static_cast<size_t>(o.landmark)].data();
    if (o.dimension() == 3) {
      ceres_problem.AddResidualBlock(new OffsetStereoCost(problem.camera, o), &huber_stereo, pose,
                                     point, &offset);
      ++estimate.stereo_observations;
    } else {
      ceres_problem.AddResidualBlock(newReprojectionCost(problem.camera, o), &huber_mono, pose,
                                     point);
    }
    pose_used[static_cast<size_t>(o.keyframe)] = 1;
  }
  if (estimate.stereo_observations < config.min_stereo_observations) {
    return failed(std::to_string(estimate.stereo_observations) + " stereo observations, " +
                  std::to_string(config.min_stereo_observations) + " needed");
  }
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (size_t l = 0; l < points.size(); ++l) {
    if (use[l]) ordering->AddElementToGroup(points[l].data(), 0);
  }
  bool any_fixed_used = false;
  for (size_t k = 0; k < poses.size(); ++k) {
    if (!pose_used[k]) continue;
    ordering->AddElementToGroup(poses[k].data(), 1);
    if (problem.keyframes[k].fixed) {
      ceres_problem.SetParameterBlockConstant(poses[k].data());
      any_fixed_used = true;
    } else {
      ceres_problem.SetManifold(poses[k].data(), &manifold);
    }
  }
  if (!any_fixed_used) return failed("no fixed keyframe observes the landmarks used");
  ordering->AddElementToGroup(&offset, 1);

  ceres::Solver::Options options = solverOptions(CeresSolverConfig{}, config.iterations, 0.0);
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.linear_solver_ordering = ordering;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &ceres_problem, &summary);
  if (!summary.IsSolutionUsable() || !std::isfinite(offset)) {
    return failed("the solve failed: " + summary.message);
  }
  estimate.ok = true;
  estimate.offset_px = offset;
  estimate.landmarks = landmarks;
  estimate.initial_cost = summary.initial_cost;
  estimate.final_cost = summary.final_cost;
  return estimate;
}

}  // namespace cblox
