#include "core/covariance/sparse_solve_solver.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cblox {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

namespace {

// One block column B of the forward solve for several keyframes at once: for each block
// k < count below B (row block rows[k], L[k] = L_RB) and each slot t of `slots`,
// panel[R m + t] -= L[k] panel[B m + t] (column-major 6 x 6 blocks; slot t's panel of block
// column X is panel[X m + t]). L[k] is read once for all the slots. The portable kernel:
// Eigen's fixed-size product.
void updateBelowPortable(const Matrix6d* L, const int* rows, int count, const int* slots,
                         int num_slots, int m, int B, Matrix6d* panel) {
  for (int k = 0; k < count; ++k) {
    for (int a = 0; a < num_slots; ++a) {
      const int t = slots[a];
      panel[rows[k] * m + t].noalias() -= L[k] * panel[B * m + t];
    }
  }
}

#if defined(__x86_64__)
// The same with AVX2 + FMA: each 6-row column of a block is a 4-lane and a 2-lane register;
// column c of the update takes 6 fused multiply-subtracts per half, one per column of L[k]
// (held in registers across the slots), times the broadcast Y(j, c). 72 FMAs per block
// instead of Eigen's 216 SSE2 multiplies and adds; the sums are the same up to FMA's
// rounding.
__attribute__((target("avx2,fma"))) void updateBelowAvx2(const Matrix6d* L, const int* rows,
                                                         int count, const int* slots, int num_slots,
                                                         int m, int B, Matrix6d* panel) {
  for (int k = 0; k < count; ++k) {
    const double* l = L[k].data();
    __m256d lo[6];
    __m128d hi[6];
    for (int j = 0; j < 6; ++j) {
      lo[j] = _mm256_loadu_pd(l + 6 * j);
      hi[j] = _mm_loadu_pd(l + 6 * j + 4);
    }
    for (int a = 0; a < num_slots; ++a) {
      const int t = slots[a];
      const double* y = panel[B * m + t].data();
      double* w = panel[rows[k] * m + t].data();
      for (int c = 0; c < 6; ++c) {
        __m256d acc_lo = _mm256_loadu_pd(w + 6 * c);
        __m128d acc_hi = _mm_loadu_pd(w + 6 * c + 4);
        for (int j = 0; j < 6; ++j) {
          const __m256d b = _mm256_broadcast_sd(y + 6 * c + j);
          acc_lo = _mm256_fnmadd_pd(lo[j], b, acc_lo);
          acc_hi = _mm_fnmadd_pd(hi[j], _mm256_castpd256_pd128(b), acc_hi);
        }
        _mm256_storeu_pd(w + 6 * c, acc_lo);
        _mm_storeu_pd(w + 6 * c + 4, acc_hi);
      }
    }
  }
}

bool hasAvx2Fma() {
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
}
#endif

}  // namespace

std::string validate(const SparseSolveCovarianceSolverConfig& config) {
  if (config.ordering != BlockOrdering::kAmd &&
      config.ordering != BlockOrdering::kNestedDissection) {
    return "ordering is not a BlockOrdering value";
  }
  return validateFactorField(config.factor);
}

SparseSolveCovarianceSolver::SparseSolveCovarianceSolver(
    ReducedCameraMatrix S, const SparseSolveCovarianceSolverConfig& config)
    : S_(std::move(S)),
      config_(validatedConfig(config, "SparseSolveCovarianceSolver")),
      A_(S_.matrix) {
  update_below_ = updateBelowPortable;
#if defined(__x86_64__)
  if (config_.vectorized && hasAvx2Fma()) update_below_ = updateBelowAvx2;
#endif
  const std::vector<int> block_perm = blockOrdering(S_, config_.ordering);
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
  slots_.assign(S_.numBlocks(), {});
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
  if (cache_slot_[block] < 0) solveTogether(std::span<const int>(&block, 1));
  return cache_[cache_slot_[block]];
}

void SparseSolveCovarianceSolver::solveTogether(std::span<const int> blocks) {
  // At most kMaxTogether keyframes per sweep: the panels take m 6 x 6 blocks per block column.
  for (size_t start = 0; start < blocks.size(); start += kMaxTogether) {
    const std::span<const int> chunk =
        blocks.subspan(start, std::min(kMaxTogether, blocks.size() - start));
    const int m = static_cast<int>(chunk.size());
    const int nb = S_.numBlocks();
    if (panel_.size() < static_cast<size_t>(nb) * m) panel_.resize(static_cast<size_t>(nb) * m);
    // Each keyframe's reach: its path to the root of the block elimination tree (parents have
    // larger indices, so a path is in topological, increasing order). The sweep visits the
    // union of the paths in increasing order; slots_[B] lists the keyframes whose path holds B.
    std::vector<std::vector<int>> paths(m);
    std::vector<int> sweep;
    for (int t = 0; t < m; ++t) {
      for (int B = position_[chunk[t]]; B >= 0; B = block_parent_[B]) {
        paths[t].push_back(B);
        if (slots_[B].empty()) sweep.push_back(B);
        slots_[B].push_back(t);
        panel_[static_cast<size_t>(B) * m + t].setZero();
      }
      // L Y = P E_a: the right-hand side is the identity on the keyframe's own pivots.
      panel_[static_cast<size_t>(paths[t].front()) * m + t].setIdentity();
    }
    std::sort(sweep.begin(), sweep.end());
    for (const int B : sweep) {
      const std::vector<int>& slots = slots_[B];
      for (const int t : slots) {
        diagonal_[B].triangularView<Eigen::Lower>().solveInPlace(
            panel_[static_cast<size_t>(B) * m + t]);
      }
      const int first = below_ptr_[B], count = below_ptr_[B + 1] - first;
      update_below_(below_.data() + first, below_row_.data() + first, count, slots.data(),
                    static_cast<int>(slots.size()), m, B, panel_.data());
    }
    for (int t = 0; t < m; ++t) {
      Solution& y = cache_.emplace_back();
      y.blocks = std::move(paths[t]);
      y.values.reserve(y.blocks.size());
      std::int64_t stored_blocks = 0;
      for (const int B : y.blocks) {
        y.values.push_back(panel_[static_cast<size_t>(B) * m + t]);
        stored_blocks += 1 + below_ptr_[B + 1] - below_ptr_[B];
      }
      cache_slot_[chunk[t]] = static_cast<int>(cache_.size()) - 1;
      ++stats_.keyframes_solved;
      stats_.reached_columns += 6 * static_cast<std::int64_t>(y.blocks.size());
      stats_.flops += 432.0 * static_cast<double>(stored_blocks);
    }
    for (const int B : sweep) slots_[B].clear();
  }
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
  if (factor_error_.empty()) {
    // Every keyframe the pairs need (the cache is empty), solved in shared sweeps: each block
    // of L is read once per sweep for all of them.
    std::vector<int> needed;
    for (const KeyframePair& pair : pairs) {
      for (const std::uint64_t id : {pair.i, pair.j}) {
        if (const int block = S_.blockOf(id); block >= 0) needed.push_back(block);
      }
    }
    std::sort(needed.begin(), needed.end());
    needed.erase(std::unique(needed.begin(), needed.end()), needed.end());
    solveTogether(needed);
  }
  return computeValidPairs(S_, pairs, factor_error_, [&](const KeyframePair& pair) {
    const Solution& yi = solutionOf(S_.blockOf(pair.i));
    const Solution& yj = solutionOf(S_.blockOf(pair.j));
    return conditionalFromCovarianceBlocks(pair, crossProduct(yi, yi), crossProduct(yi, yj),
                                           crossProduct(yj, yj));
  });
}

}  // namespace cblox
