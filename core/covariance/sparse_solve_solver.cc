#include "core/covariance/sparse_solve_solver.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "core/covariance/block_ordering.h"

namespace cblox {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

std::string validate(const SparseSolveCovarianceSolverConfig& config) {
  return validateFactorField(config.factor);
}

SparseSolveCovarianceSolver::SparseSolveCovarianceSolver(
    ReducedCameraMatrix S, const SparseSolveCovarianceSolverConfig& config)
    : S_(std::move(S)),
      config_(validatedConfig(config, "SparseSolveCovarianceSolver")),
      A_(S_.matrix) {
  const std::vector<int> block_perm = blockAmdOrdering(S_);
  CholmodFactorOutcome f = factorizeSimplicialWithPermutation(
      common_, A_, expandBlockPermutation(block_perm), config_.factor, S_.keyframe_ids);
  if (!f.ok) {
    factor_error_ = std::move(f.error);
    return;
  }
  factor_ = std::move(f.factor);
  const cholmod_factor& L = *factor_.get();
  const int n = static_cast<int>(L.n);
  const int* p = static_cast<const int*>(L.p);
  const int* row = static_cast<const int*>(L.i);
  const int* nz = static_cast<const int*>(L.nz);
  // The parent of column c in the elimination tree is its first off-diagonal row (the
  // smallest: rows are not assumed sorted).
  parent_.assign(n, -1);
  for (int c = 0; c < n; ++c) {
    int parent = n;
    for (int q = p[c] + 1; q < p[c] + nz[c]; ++q) parent = std::min(parent, row[q]);
    parent_[c] = parent < n ? parent : -1;
    factor_nnz_ += nz[c];
  }
  first_pivot_.assign(S_.numBlocks(), 0);
  for (int k = 0; k < S_.numBlocks(); ++k) first_pivot_[block_perm[k]] = 6 * k;
  cache_slot_.assign(S_.numBlocks(), -1);
  work_.setZero(n, 6);
  marked_.assign(n, 0);
}

void SparseSolveCovarianceSolver::clearCache() {
  std::fill(cache_slot_.begin(), cache_slot_.end(), -1);
  cache_.clear();
  stats_ = {};
}

const SparseSolveCovarianceSolver::Solution& SparseSolveCovarianceSolver::solutionOf(int block) {
  if (cache_slot_[block] >= 0) return cache_[cache_slot_[block]];
  return solve(block);
}

const SparseSolveCovarianceSolver::Solution& SparseSolveCovarianceSolver::solve(int block) {
  const cholmod_factor& L = *factor_.get();
  const int* p = static_cast<const int*>(L.p);
  const int* row = static_cast<const int*>(L.i);
  const int* nz = static_cast<const int*>(L.nz);
  const double* x = static_cast<const double*>(L.x);

  // Reach of the block's 6 pivot columns: the union of their etree paths to the root.
  Solution& y = cache_.emplace_back();
  const int c0 = first_pivot_[block];
  for (int q = 0; q < 6; ++q) {
    for (int c = c0 + q; c >= 0 && !marked_[c]; c = parent_[c]) {
      marked_[c] = 1;
      y.rows.push_back(c);
    }
  }
  // Parents have larger indices than their children: increasing order is topological.
  std::sort(y.rows.begin(), y.rows.end());

  // L Y = P E_a column by column over the reach, the 6 right-hand sides at once.
  for (int q = 0; q < 6; ++q) work_(c0 + q, q) = 1.0;
  std::int64_t entries = 0;
  for (const int c : y.rows) {
    const int begin = p[c];
    const int end = p[c] + nz[c];
    work_.row(c) /= x[begin];
    const Eigen::Matrix<double, 1, 6> yc = work_.row(c);
    for (int q = begin + 1; q < end; ++q) work_.row(row[q]) -= x[q] * yc;
    entries += end - begin;
  }
  y.values.resize(static_cast<Eigen::Index>(y.rows.size()), 6);
  for (size_t k = 0; k < y.rows.size(); ++k) {
    const int c = y.rows[k];
    y.values.row(static_cast<Eigen::Index>(k)) = work_.row(c);
    work_.row(c).setZero();
    marked_[c] = 0;
  }
  cache_slot_[block] = static_cast<int>(cache_.size()) - 1;
  ++stats_.keyframes_solved;
  stats_.reached_columns += static_cast<std::int64_t>(y.rows.size());
  stats_.flops += 12.0 * static_cast<double>(entries);
  return y;
}

namespace {

// Y_a^T Y_b over the rows both reach (sorted lists: a merge).
template <typename Solution>
Matrix6d crossProduct(const Solution& a, const Solution& b) {
  if (&a == &b) return a.values.transpose() * a.values;
  Matrix6d sum = Matrix6d::Zero();
  size_t ka = 0, kb = 0;
  while (ka < a.rows.size() && kb < b.rows.size()) {
    if (a.rows[ka] < b.rows[kb]) {
      ++ka;
    } else if (b.rows[kb] < a.rows[ka]) {
      ++kb;
    } else {
      sum.noalias() += a.values.row(static_cast<Eigen::Index>(ka)).transpose() *
                       b.values.row(static_cast<Eigen::Index>(kb));
      ++ka;
      ++kb;
    }
  }
  return sum;
}

}  // namespace

Matrix6d SparseSolveCovarianceSolver::covarianceBlock(std::uint64_t a, std::uint64_t b) {
  if (!factor_) throw std::logic_error("SparseSolveCovarianceSolver: " + factor_error_);
  const int block_a = S_.blockOf(a);
  const int block_b = S_.blockOf(b);
  for (const auto& [id, block] : {std::pair{a, block_a}, std::pair{b, block_b}}) {
    if (block < 0) {
      throw std::invalid_argument("SparseSolveCovarianceSolver::covarianceBlock: keyframe " +
                                  std::to_string(id) + " has no block in S");
    }
  }
  const Solution& ya = solutionOf(block_a);
  const Solution& yb = solutionOf(block_b);
  return crossProduct(ya, yb);
}

std::vector<ConditionalCovariance> SparseSolveCovarianceSolver::compute(
    std::span<const KeyframePair> pairs) {
  clearCache();
  return computeValidPairs(S_, pairs, factor_error_, [&](const KeyframePair& pair) {
    const Solution& yi = solutionOf(S_.blockOf(pair.i));
    const Solution& yj = solutionOf(S_.blockOf(pair.j));
    return conditionalFromCovarianceBlocks(pair, crossProduct(yi, yi), crossProduct(yi, yj),
                                           crossProduct(yj, yj));
  });
}

}  // namespace cblox
