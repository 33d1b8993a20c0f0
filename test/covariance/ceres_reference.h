#pragma once

// Sigma_{i|j} from ceres::Covariance on the same BA problem (the reference of the tests
// and the benchmark): the observations included in the linearization, ReprojectionCost,
// SE3Manifold on the free keyframes, fixed keyframes constant; no loss function, or Ceres'
// HuberLoss with apply_loss_function when the linearization applied the robust loss (Ceres'
// Corrector then scales the rows exactly as linearizeBundleAdjustment does).

#include <array>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <ceres/covariance.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>

#include "core/covariance/conditional_covariance.h"
#include "core/optimization/ba_linearization.h"
#include "core/optimization/bundle_adjustment.h"
#include "core/optimization/se3_manifold.h"

namespace cblox::test {

class CeresCovarianceReference {
 public:
  CeresCovarianceReference(const BundleAdjustmentProblem& problem, const BaLinearization& lin,
                           const BaLinearizationConfig& config = {})
      : problem_(problem), robust_(config.apply_robust_loss) {
    ceres::Problem::Options options;
    options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres_ = std::make_unique<ceres::Problem>(options);
    poses_.reserve(problem.keyframes.size());
    for (const BaKeyframe& kf : problem.keyframes) poses_.push_back(toPoseParameters(kf.T_C_G));
    points_.reserve(problem.landmarks.size());
    for (const BaLandmark& lm : problem.landmarks) {
      points_.push_back({lm.p_G.x(), lm.p_G.y(), lm.p_G.z()});
    }
    std::vector<std::uint8_t> used(problem.keyframes.size(), 0);
    for (size_t o = 0; o < problem.observations.size(); ++o) {
      if (lin.observation_rows[o] < 0) continue;
      const BaObservation& obs = problem.observations[o];
      ceres::LossFunction* loss = nullptr;  // owned by ceres_
      if (robust_) {
        loss = new ceres::HuberLoss(obs.dimension() == 3 ? config.huber_delta_stereo
                                                         : config.huber_delta_mono);
      }
      ceres_->AddResidualBlock(newReprojectionCost(problem.camera, obs), loss,
                               poses_[obs.keyframe].data(), points_[obs.landmark].data());
      used[obs.keyframe] = 1;
    }
    for (size_t k = 0; k < problem.keyframes.size(); ++k) {
      if (!used[k]) continue;
      if (problem.keyframes[k].fixed) {
        ceres_->SetParameterBlockConstant(poses_[k].data());
      } else {
        ceres_->SetManifold(poses_[k].data(), &manifold_);
      }
    }
  }

  /// Sigma_{i|j} per pair from one ceres::Covariance::Compute over the blocks (i,i), (i,j),
  /// (j,j) of all pairs. Pairs with unknown ids are not supported (the ids must be free
  /// keyframes of the problem). Returns an empty vector if Compute fails.
  std::vector<ConditionalCovariance> compute(std::span<const KeyframePair> pairs,
                                             ceres::CovarianceAlgorithmType algorithm,
                                             int num_threads = 1) {
    ceres::Covariance::Options options;
    options.algorithm_type = algorithm;
    options.num_threads = num_threads;
    options.apply_loss_function = robust_;
    ceres::Covariance covariance(options);
    std::vector<std::pair<const double*, const double*>> blocks;
    for (const KeyframePair& p : pairs) {
      const double* a = poseOf(p.i);
      const double* b = poseOf(p.j);
      blocks.emplace_back(a, a);
      blocks.emplace_back(a, b);
      blocks.emplace_back(b, b);
    }
    std::sort(blocks.begin(), blocks.end());
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    if (!covariance.Compute(blocks, ceres_.get())) return {};
    std::vector<ConditionalCovariance> out;
    for (const KeyframePair& p : pairs) {
      const double* a = poseOf(p.i);
      const double* b = poseOf(p.j);
      Eigen::Matrix<double, 6, 6, Eigen::RowMajor> ii, ij, jj;
      covariance.GetCovarianceBlockInTangentSpace(a, a, ii.data());
      covariance.GetCovarianceBlockInTangentSpace(a, b, ij.data());
      covariance.GetCovarianceBlockInTangentSpace(b, b, jj.data());
      out.push_back(conditionalFromCovarianceBlocks(p, ii, ij, jj));
    }
    return out;
  }

 private:
  const double* poseOf(std::uint64_t id) const {
    for (size_t k = 0; k < problem_.keyframes.size(); ++k) {
      if (problem_.keyframes[k].id == id) return poses_[k].data();
    }
    return nullptr;
  }

  const BundleAdjustmentProblem& problem_;
  bool robust_ = false;
  SE3Manifold manifold_;
  std::vector<PoseParameters> poses_;
  std::vector<std::array<double, 3>> points_;
  std::unique_ptr<ceres::Problem> ceres_;
};

}  // namespace cblox::test
