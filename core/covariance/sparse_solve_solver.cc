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
  position_.assign(S_.numBlocks(), 0);
  for (int k = 0; k < S_.numBlocks(); ++k) position_[block_perm[k]] = k;
  storeBlocks(*f.factor.get());  // CHOLMOD's copy is freed on return
  cache_slot_.assign(S_.numBlocks(), -1);
  work_.assign(S_.numBlocks(), Matrix6d::Zero());
}

void SparseSolveCovarianceSolver::storeBlocks(const cholmod_factor& L) {
  const int nb = S_.numBlocks();
  const int* p = static_cast<const int*>(L.p);
  const int* row = static_cast<const int*>(L.i);
  const int* nz = static_cast<const int*>(L.nz);
  const double* x = static_cast<const double*>(L.x);
  diagonal_.assign(nb, Matrix6d::Zero());
  block_parent_.assign(nb, -1);
  below_ptr_.assign(nb + 1, 0);
  below_row_.clear();
  below_.clear();
  std::vector<int> slot(nb, -1);  // row block -> index into below_ within the current column
  for (int B = 0; B < nb; ++B) {
    const int first = static_cast<int>(below_.size());
    for (int q = 0; q < 6; ++q) {
      const int c = 6 * B + q;
      factor_nnz_ += nz[c];
      for (int e = p[c]; e < p[c] + nz[c]; ++e) {
        const int R = row[e] / 6;
        if (R == B) {
          diagonal_[B](row[e] % 6, q) = x[e];
          continue;
        }
        if (slot[R] < 0) {
          slot[R] = static_cast<int>(below_.size());
          below_row_.push_back(R);
          below_.push_back(Matrix6d::Zero());
        }
        below_[slot[R]](row[e] % 6, q) = x[e];
      }
    }
    int parent = nb;
    for (size_t k = first; k < below_.size(); ++k) {
      parent = std::min(parent, below_row_[k]);
      slot[below_row_[k]] = -1;
    }
    block_parent_[B] = parent < nb ? parent : -1;
    below_ptr_[B + 1] = static_cast<int>(below_.size());
  }
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
  // Reach of the block column: its path to the root of the block elimination tree (parents
  // have larger indices, so the path is already in topological, increasing order).
  Solution& y = cache_.emplace_back();
  for (int B = position_[block]; B >= 0; B = block_parent_[B]) y.blocks.push_back(B);

  // L Y = P E_a over the reach, the 6 right-hand sides at once, block by block.
  work_[y.blocks.front()].setIdentity();
  std::int64_t stored_blocks = 0;
  for (const int B : y.blocks) {
    diagonal_[B].triangularView<Eigen::Lower>().solveInPlace(work_[B]);
    const Matrix6d& yb = work_[B];
    for (int k = below_ptr_[B]; k < below_ptr_[B + 1]; ++k) {
      work_[below_row_[k]].noalias() -= below_[k] * yb;
    }
    stored_blocks += 1 + below_ptr_[B + 1] - below_ptr_[B];
  }
  y.values.reserve(y.blocks.size());
  for (const int B : y.blocks) {
    y.values.push_back(work_[B]);
    work_[B].setZero();
  }
  cache_slot_[block] = static_cast<int>(cache_.size()) - 1;
  ++stats_.keyframes_solved;
  stats_.reached_columns += 6 * static_cast<std::int64_t>(y.blocks.size());
  stats_.flops += 432.0 * static_cast<double>(stored_blocks);
  return y;
}

namespace {

// Y_a^T Y_b over the blocks both reach (sorted lists: a merge).
template <typename Solution>
Matrix6d crossProduct(const Solution& a, const Solution& b) {
  Matrix6d sum = Matrix6d::Zero();
  size_t ka = 0, kb = 0;
  while (ka < a.blocks.size() && kb < b.blocks.size()) {
    if (a.blocks[ka] < b.blocks[kb]) {
      ++ka;
    } else if (b.blocks[kb] < a.blocks[ka]) {
      ++kb;
    } else {
      sum.noalias() += a.values[ka].transpose() * b.values[kb];
      ++ka;
      ++kb;
    }
  }
  return sum;
}

}  // namespace

Matrix6d SparseSolveCovarianceSolver::covarianceBlock(std::uint64_t a, std::uint64_t b) {
  if (!factor_error_.empty()) {
    throw std::logic_error("SparseSolveCovarianceSolver: " + factor_error_);
  }
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

ConditionalCovariance SparseSolveCovarianceSolver::marginal(const KeyframePair& pair) {
  if (std::string e = marginalIdError(S_, pair); !e.empty()) return failedPair(pair, std::move(e));
  if (!factor_error_.empty()) return failedPair(pair, factor_error_);
  const Solution& y = solutionOf(S_.blockOf(pair.i));
  return conditionalGivenFixed(pair, crossProduct(y, y));
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
