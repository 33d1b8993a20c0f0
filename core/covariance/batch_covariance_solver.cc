#include "core/covariance/batch_covariance_solver.h"

#include "core/covariance/block_ordering.h"

namespace cblox {

std::string validate(const BatchCovarianceSolverConfig& config) {
  return validateFactorField(config.factor);
}

BatchCovarianceSolver::BatchCovarianceSolver(ReducedCameraMatrix S,
                                             const BatchCovarianceSolverConfig& config)
    : S_(std::move(S)), config_(validatedConfig(config, "BatchCovarianceSolver")), A_(S_.matrix) {}

std::vector<ConditionalCovariance> BatchCovarianceSolver::compute(
    std::span<const KeyframePair> pairs) {
  const int K = S_.numBlocks();
  std::vector<ConditionalCovariance> out(pairs.size());
  std::vector<int> constraint(K, 0);
  int m = 0;
  for (size_t p = 0; p < pairs.size(); ++p) {
    if (std::string e = pairIdError(S_, pairs[p]); !e.empty()) {
      out[p] = failedPair(pairs[p], std::move(e));
      continue;
    }
    for (const std::uint64_t id : {pairs[p].i, pairs[p].j}) {
      int& c = constraint[S_.blockOf(id)];
      if (c == 0) ++m;
      c = 1;
    }
  }
  if (m == 0) return out;

  Eigen::MatrixXd sigma_TT;
  std::vector<int> slot;
  if (std::string e = trailingCovariance(constraint, m, &sigma_TT, &slot); !e.empty()) {
    for (size_t p = 0; p < pairs.size(); ++p) {
      if (out[p].error.empty()) out[p] = failedPair(pairs[p], e);
    }
    return out;
  }
  for (size_t p = 0; p < pairs.size(); ++p) {
    if (!out[p].error.empty()) continue;
    const int a = 6 * slot[S_.blockOf(pairs[p].i)];
    const int b = 6 * slot[S_.blockOf(pairs[p].j)];
    out[p] =
        conditionalFromCovarianceBlocks(pairs[p], sigma_TT.block<6, 6>(a, a),
                                        sigma_TT.block<6, 6>(a, b), sigma_TT.block<6, 6>(b, b));
  }
  return out;
}

ConditionalCovariance BatchCovarianceSolver::marginal(const KeyframePair& pair) {
  if (std::string e = marginalIdError(S_, pair); !e.empty()) return failedPair(pair, std::move(e));
  std::vector<int> constraint(S_.numBlocks(), 0);
  constraint[S_.blockOf(pair.i)] = 1;
  Eigen::MatrixXd sigma_TT;
  std::vector<int> slot;
  if (std::string e = trailingCovariance(constraint, 1, &sigma_TT, &slot); !e.empty()) {
    return failedPair(pair, std::move(e));
  }
  return conditionalGivenFixed(pair, sigma_TT.topLeftCorner<6, 6>());
}

std::string BatchCovarianceSolver::trailingCovariance(const std::vector<int>& constraint, int m,
                                                      Eigen::MatrixXd* sigma_TT,
                                                      std::vector<int>* slot) {
  const int K = S_.numBlocks();
  const std::vector<int> block_perm = constrainedBlockOrdering(S_, constraint);
  CholmodFactorOutcome f = factorizeWithPermutation(common_, A_, expandBlockPermutation(block_perm),
                                                    config_.factor, S_.keyframe_ids);
  if (!f.ok) return f.error;
  // Slot of each constrained block in the trailing m blocks.
  slot->assign(K, -1);
  for (int s = 0; s < m; ++s) (*slot)[block_perm[K - m + s]] = s;
  const Eigen::MatrixXd L_TT = trailingFactorBlock(*f.factor.get(), 6 * m);
  const Eigen::MatrixXd X =
      L_TT.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(6 * m, 6 * m));
  *sigma_TT = X.transpose() * X;
  return {};
}

}  // namespace cblox
