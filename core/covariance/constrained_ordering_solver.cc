#include "core/covariance/constrained_ordering_solver.h"

#include "core/covariance/block_ordering.h"

namespace cblox {

std::string validate(const ConstrainedOrderingSolverConfig& config) {
  return validateFactorField(config.factor);
}

ConstrainedOrderingSolver::ConstrainedOrderingSolver(ReducedCameraMatrix S,
                                                     const ConstrainedOrderingSolverConfig& config)
    : S_(std::move(S)),
      config_(validatedConfig(config, "ConstrainedOrderingSolver")),
      A_(S_.matrix) {}

std::vector<ConditionalCovariance> ConstrainedOrderingSolver::compute(
    std::span<const KeyframePair> pairs) {
  std::vector<ConditionalCovariance> out;
  out.reserve(pairs.size());
  for (const KeyframePair& pair : pairs) out.push_back(computePair(pair));
  return out;
}

CholmodFactorOutcome ConstrainedOrderingSolver::factorWithLast(std::initializer_list<int> last) {
  std::vector<int> constraint(S_.numBlocks(), 0);
  int set = 0;
  for (const int block : last) constraint[block] = ++set;
  const std::vector<int> perm = expandBlockPermutation(constrainedBlockOrdering(S_, constraint));
  return factorizeWithPermutation(common_, A_, perm, config_.factor, S_.keyframe_ids);
}

ConditionalCovariance ConstrainedOrderingSolver::computePair(const KeyframePair& pair) {
  if (std::string e = pairIdError(S_, pair); !e.empty()) return failedPair(pair, std::move(e));
  CholmodFactorOutcome f = factorWithLast({S_.blockOf(pair.i), S_.blockOf(pair.j)});
  if (!f.ok) return failedPair(pair, std::move(f.error));
  const Eigen::MatrixXd L22 = trailingFactorBlock(*f.factor.get(), 12);
  return conditionalFromFactorBlock(pair, L22.topLeftCorner<6, 6>());
}

ConditionalCovariance ConstrainedOrderingSolver::marginal(const KeyframePair& pair) {
  if (std::string e = marginalIdError(S_, pair); !e.empty()) return failedPair(pair, std::move(e));
  CholmodFactorOutcome f = factorWithLast({S_.blockOf(pair.i)});
  if (!f.ok) return failedPair(pair, std::move(f.error));
  return conditionalFromFactorBlock(pair, trailingFactorBlock(*f.factor.get(), 6));
}

}  // namespace cblox
