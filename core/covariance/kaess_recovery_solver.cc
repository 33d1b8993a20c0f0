#include "core/covariance/kaess_recovery_solver.h"

#include <utility>

#include "core/covariance/block_ordering.h"

namespace cblox {

std::string validate(const KaessRecoverySolverConfig& config) {
  return validateFactorField(config.factor);
}

KaessRecoverySolver::KaessRecoverySolver(ReducedCameraMatrix S,
                                         const KaessRecoverySolverConfig& config)
    : S_(std::move(S)), config_(validatedConfig(config, "KaessRecoverySolver")), A_(S_.matrix) {
  const std::vector<int> perm = expandBlockPermutation(blockAmdOrdering(S_));
  CholmodFactorOutcome f =
      factorizeSimplicialWithPermutation(common_, A_, perm, config_.factor, S_.keyframe_ids);
  if (!f.ok) {
    factor_error_ = std::move(f.error);
    return;
  }
  factor_ = std::move(f.factor);
  position_.assign(perm.size(), 0);
  for (size_t k = 0; k < perm.size(); ++k) position_[perm[k]] = static_cast<int>(k);
}

double KaessRecoverySolver::permutedEntry(int i0, int l0) {
  const cholmod_factor& L = *factor_.get();
  const std::uint64_t n = L.n;
  const int* p = static_cast<const int*>(L.p);
  const int* row = static_cast<const int*>(L.i);
  const int* nz = static_cast<const int*>(L.nz);
  const double* x = static_cast<const double*>(L.x);
  auto key = [n](int a, int b) { return static_cast<std::uint64_t>(a) * n + b; };
  if (i0 > l0) std::swap(i0, l0);
  if (const auto it = cache_.find(key(i0, l0)); it != cache_.end()) return it->second;

  stack_.clear();
  stack_.emplace_back(i0, l0);
  while (!stack_.empty()) {
    const auto [i, l] = stack_.back();  // i <= l
    if (cache_.contains(key(i, l))) {
      stack_.pop_back();
      continue;
    }
    bool ready = true;
    double sum = 0.0;
    const int begin = p[i];
    const int end = p[i] + nz[i];
    for (int q = begin + 1; q < end; ++q) {  // skip the diagonal (first entry)
      const int j = row[q];                  // j > i
      const int a = std::min(j, l);
      const int b = std::max(j, l);
      const auto it = cache_.find(key(a, b));
      if (it == cache_.end()) {
        stack_.emplace_back(a, b);
        ready = false;
      } else if (ready) {
        sum += x[q] * it->second;
      }
    }
    if (!ready) continue;
    const double r_ii = x[begin];
    cache_.emplace(key(i, l), ((i == l ? 1.0 / r_ii : 0.0) - sum) / r_ii);
    stack_.pop_back();
  }
  return cache_.at(key(i0, l0));
}

double KaessRecoverySolver::covarianceEntry(int row, int col) {
  if (!factor_) throw std::logic_error("KaessRecoverySolver: " + factor_error_);
  const int n = static_cast<int>(position_.size());
  if (row < 0 || row >= n || col < 0 || col >= n) {
    throw std::out_of_range("KaessRecoverySolver::covarianceEntry: index outside [0, " +
                            std::to_string(n) + ")");
  }
  return permutedEntry(position_[row], position_[col]);
}

Eigen::Matrix<double, 6, 6> KaessRecoverySolver::covarianceBlock(int a, int b) {
  Eigen::Matrix<double, 6, 6> block;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      if (a == b && c < r) continue;  // symmetric: the upper triangle, mirrored
      block(r, c) = permutedEntry(position_[a + r], position_[b + c]);
      if (a == b) block(c, r) = block(r, c);
    }
  }
  return block;
}

std::vector<ConditionalCovariance> KaessRecoverySolver::compute(
    std::span<const KeyframePair> pairs) {
  return computeValidPairs(S_, pairs, factor_error_, [&](const KeyframePair& pair) {
    if (!config_.cache_across_pairs) cache_.clear();
    const int a = 6 * S_.blockOf(pair.i);
    const int b = 6 * S_.blockOf(pair.j);
    return conditionalFromCovarianceBlocks(pair, covarianceBlock(a, a), covarianceBlock(a, b),
                                           covarianceBlock(b, b));
  });
}

ConditionalCovariance KaessRecoverySolver::marginal(const KeyframePair& pair) {
  if (std::string e = marginalIdError(S_, pair); !e.empty()) return failedPair(pair, std::move(e));
  if (!factor_error_.empty()) return failedPair(pair, factor_error_);
  if (!config_.cache_across_pairs) cache_.clear();
  const int a = 6 * S_.blockOf(pair.i);
  return conditionalGivenFixed(pair, covarianceBlock(a, a));
}

}  // namespace cblox
