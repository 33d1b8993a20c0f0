#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "core/optimization/cholmod_support.h"
#include "core/covariance/conditional_covariance.h"
#include "core/covariance/reduced_camera_matrix.h"

namespace cblox {

struct KaessRecoverySolverConfig {
  /// Factor kind and positive-definiteness test (defaults: kAuto, 1e-10). A
  /// supernodal factor is converted once to simplicial LL^T for the recovery.
  CholmodFactorConfig factor;
  /// Keep recovered entries of S^-1 between pairs (they do not change: later pairs reuse
  /// them). false clears the cache before every pair (each pair then pays its full cost).
  /// Default true.
  bool cache_across_pairs = true;
};

/// Empty if valid, else a message naming the bad field. Thread-safe (pure).
std::string validate(const KaessRecoverySolverConfig& config);

/// The reference method: ONE unconstrained ordering (AMD on S's block pattern, expanded to
/// scalars, forced through CHOLMOD) and ONE factorisation at construction, then per pair
/// only the needed entries of Sigma = S^-1 (blocks ii, ij, jj) by the recursion of Kaess &
/// Dellaert, "Covariance recovery from a square root information matrix for data
/// association", RAS 2009. With R = L^T (upper triangular) and Sigma' = (R^T R)^-1 the
/// covariance in the permuted order, R Sigma' = R^-T is lower triangular with diagonal
/// 1 / r_ii, so for i <= l (row i of R = column i of L, nz = its sparsity):
///   sigma'_il = (delta_il / r_ii - sum_{j in nz(r_i.), j > i} r_ij sigma'_jl) / r_ii,
/// using sigma'_jl = sigma'_lj for j > l. Entries are computed on demand (explicit stack,
/// no recursion depth limit) and memoised in a hash map; Sigma_{i|j} then comes from
/// conditionalFromCovarianceBlocks.
class KaessRecoverySolver final : public ConditionalCovarianceSolver {
 public:
  /// Orders and factorises S (a failure is remembered and reported per pair). Takes S by
  /// value (move it in to avoid a copy). Throws std::invalid_argument if the config is
  /// invalid.
  explicit KaessRecoverySolver(ReducedCameraMatrix S, const KaessRecoverySolverConfig& config = {});
  using ConditionalCovarianceSolver::compute;
  /// Recovery only (no factorisation). Not thread-safe (fills the cache).
  std::vector<ConditionalCovariance> compute(std::span<const KeyframePair> pairs) override;
  /// The 21 entries of the ii block by recovery (no factorisation).
  ConditionalCovariance marginal(const KeyframePair& pair) override;
  const ReducedCameraMatrix& reducedCameraMatrix() const override { return S_; }

  /// Empty if the factorisation succeeded, else its error. Thread-safe (const).
  const std::string& factorError() const { return factor_error_; }
  /// Entry (row, col) of S^-1 in S's scalar layout (units of the tangents' covariance).
  /// Throws std::logic_error if the factorisation failed, std::out_of_range on bad
  /// indices. Not thread-safe (fills the cache).
  double covarianceEntry(int row, int col);
  /// Number of memoised entries of S^-1 (upper triangle, permuted order). Thread-safe
  /// (const).
  size_t cacheSize() const { return cache_.size(); }
  /// Empties the cache. Not thread-safe.
  void clearCache() { cache_.clear(); }

 private:
  double permutedEntry(int i, int l);  // i, l in pivot order
  // The 6x6 block (a, b) of S^-1 (a, b: first scalar indices of two blocks of S).
  Eigen::Matrix<double, 6, 6> covarianceBlock(int a, int b);

  ReducedCameraMatrix S_;
  KaessRecoverySolverConfig config_;
  CholmodCommon common_;
  CholmodSymmetricMatrix A_;
  CholmodFactor factor_;  // simplicial LL^T
  std::string factor_error_;
  std::vector<int> position_;  // position_[scalar column of S] = pivot index
  absl::flat_hash_map<std::uint64_t, double> cache_;
  std::vector<std::pair<int, int>> stack_;
};

}  // namespace cblox
