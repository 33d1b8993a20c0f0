#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/StdVector>

#include "core/covariance/block_ordering.h"
#include "core/covariance/conditional_covariance.h"
#include "core/covariance/reduced_camera_matrix.h"
#include "core/optimization/cholmod_support.h"

namespace cblox {

struct SparseSolveCovarianceSolverConfig {
  /// Factor kind and positive-definiteness test (defaults: kAuto, 1e-10). A supernodal factor
  /// is converted once to simplicial LL^T for the sparse solves.
  CholmodFactorConfig factor;
  /// The block ordering. Nested dissection (the default) shortens every keyframe's path to
  /// the root of the elimination tree, which is what a solve costs: 1.9x fewer flops than
  /// AMD on a 500-keyframe loop (BENCHMARKS.md, "Conditional covariance extraction").
  BlockOrdering ordering = BlockOrdering::kNestedDissection;
  /// The solve's 6 x 6 block updates with AVX2 + FMA where the CPU has both (x86-64 only);
  /// false: Eigen's portable product. Both give the same covariances up to rounding.
  bool vectorized = true;
};

/// Empty if valid, else a message naming the bad field. Thread-safe (pure).
std::string validate(const SparseSolveCovarianceSolverConfig& config);

/// Work of the sparse forward solves of one compute() call (cumulative over its calls to
/// the solver until the next compute()).
struct SparseSolveStats {
  int keyframes_solved = 0;          ///< distinct keyframes whose Y_a was computed
  std::int64_t reached_columns = 0;  ///< sum over those of 6 |block reach| (columns visited)
  /// Multiply-adds * 2 of the solves (not the dot products), over the stored 6 x 6 blocks.
  double flops = 0.0;
};

/// One ordering and ONE factorisation at construction, then per keyframe a sparse forward
/// solve (beyond the paper; the fourth method of issue 6).
///
/// With P S P^T = L L^T (the configured ordering, nested dissection by default, of S's block
/// pattern expanded to scalars, forced through CHOLMOD, converted to simplicial LL^T),
/// Sigma = S^-1 = P^T L^-T L^-1 P, so the joint covariance blocks are Sigma_ab = Y_a^T Y_b
/// with Y_a = L^-1 (P E_a), E_a the 6 unit columns of keyframe a. P E_a has its nonzeros in
/// the 6 pivot columns of a, so Y_a is nonzero only on their reach in the elimination tree of
/// L (the union of their etree paths to the root; Gilbert & Peierls). Because the ordering
/// keeps each keyframe's 6 pivots together, L is copied out of CHOLMOD by 6 x 6 blocks (block
/// column = keyframe, with its lower-triangular diagonal block and the dense 6 x 6 blocks
/// below it, zero-filled where CHOLMOD stores no entry) and the solve walks the BLOCK
/// elimination tree: per reached block column B, Y_B <- L_BB^-1 Y_B, then Y_R -= L_RB Y_B for
/// each block below (fixed-size 6 x 6 products; cost 432 flops per stored block). Sigma_ii =
/// Y_i^T Y_i, Sigma_ij = Y_i^T Y_j over the common reached blocks, Sigma_jj = Y_j^T Y_j, then
/// conditionalFromCovarianceBlocks. Y_a is cached per keyframe for the pairs of one compute()
/// call (a keyframe in several pairs is solved once). Per pair the cost is that of two path
/// solves, independent of the number of pairs; the reach of a keyframe ends in the dense
/// separator at the top of the etree, which dominates it on loopy maps.
class SparseSolveCovarianceSolver final : public ConditionalCovarianceSolver {
 public:
  /// Orders and factorises S (a failure is remembered and reported per pair). Takes S by
  /// value (move it in to avoid a copy). Throws std::invalid_argument if the config is
  /// invalid.
  explicit SparseSolveCovarianceSolver(ReducedCameraMatrix S,
                                       const SparseSolveCovarianceSolverConfig& config = {});
  using ConditionalCovarianceSolver::compute;
  /// Sparse solves and dot products only (no factorisation); clears the Y cache first.
  /// Not thread-safe.
  std::vector<ConditionalCovariance> compute(std::span<const KeyframePair> pairs) override;
  const ReducedCameraMatrix& reducedCameraMatrix() const override { return S_; }

  /// Y_i^T Y_i from the factor in hand: one forward solve, no factorisation. Uses and fills
  /// the Y cache.
  ConditionalCovariance marginal(const KeyframePair& pair) override;
  /// Empty if the factorisation succeeded, else its error. Thread-safe (const).
  const std::string& factorError() const { return factor_error_; }
  /// The joint covariance block Sigma_ab (6 x 6, rows: keyframe a's tangent, columns: b's;
  /// units as in conditional_covariance.h) of two keyframes with blocks in S (a == b allowed:
  /// the marginal covariance). Uses and fills the Y cache. Throws std::logic_error if the
  /// factorisation failed, std::invalid_argument if an id has no block. Not thread-safe.
  Eigen::Matrix<double, 6, 6> covarianceBlock(std::uint64_t a, std::uint64_t b);
  /// Work since the last compute() started. Thread-safe (const).
  const SparseSolveStats& stats() const { return stats_; }
  /// nnz(L) of the factor (0 if the factorisation failed). Thread-safe (const).
  std::int64_t factorNonZeros() const { return factor_nnz_; }

 private:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  // Y_a of one keyframe: the reached block columns (increasing) and Y's 6 x 6 block on each.
  struct Solution {
    std::vector<int> blocks;
    std::vector<Matrix6d, Eigen::aligned_allocator<Matrix6d>> values;
  };
  // At most this many keyframes share one sweep of L (their panels: 16 x 288 bytes per block
  // column).
  static constexpr size_t kMaxTogether = 16;
  const Solution& solutionOf(int block);
  // Solves the keyframes of `blocks` (distinct, none cached) and caches their Y: one sweep
  // over the union of their reaches per kMaxTogether of them.
  void solveTogether(std::span<const int> blocks);
  void clearCache();
  // L by 6 x 6 blocks from the simplicial factor (see the class comment).
  void storeBlocks(const cholmod_factor& L);

  ReducedCameraMatrix S_;
  SparseSolveCovarianceSolverConfig config_;
  CholmodCommon common_;
  CholmodSymmetricMatrix A_;
  std::string factor_error_;
  std::int64_t factor_nnz_ = 0;
  std::vector<int> position_;      // position_[block] = its pivot block column in L
  std::vector<int> block_parent_;  // block elimination tree of L (-1 at a root)
  std::vector<Matrix6d, Eigen::aligned_allocator<Matrix6d>> diagonal_;  // L_BB, lower
  std::vector<int> below_ptr_;  // block column B's blocks below: [below_ptr_[B], [B + 1])
  std::vector<int> below_row_;  // their row block
  std::vector<Matrix6d, Eigen::aligned_allocator<Matrix6d>> below_;  // their L_RB
  std::vector<int> cache_slot_;  // per block: index into cache_, or -1
  std::deque<Solution> cache_;   // a deque: references stay valid as it grows
  SparseSolveStats stats_;
  // One block column's updates for the keyframes of a sweep (the AVX2 kernel or the portable
  // one; see the .cc).
  using UpdateBelow = void (*)(const Matrix6d* L, const int* rows, int count, const int* slots,
                               int num_slots, int m, int B, Matrix6d* panel);
  UpdateBelow update_below_;
  // Workspace of a sweep of m keyframes: panel_[B m + t] is keyframe t's block of Y on block
  // column B (valid on t's reach only); slots_[B] the keyframes whose reach holds B (empty
  // outside a sweep).
  std::vector<Matrix6d, Eigen::aligned_allocator<Matrix6d>> panel_;
  std::vector<std::vector<int>> slots_;
};

}  // namespace cblox
