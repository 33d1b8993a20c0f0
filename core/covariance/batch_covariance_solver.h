#pragma once

#include <span>
#include <string>
#include <vector>

#include "core/optimization/cholmod_support.h"
#include "core/covariance/conditional_covariance.h"
#include "core/covariance/reduced_camera_matrix.h"

namespace cblox {

struct BatchCovarianceSolverConfig {
  /// Factor kind and positive-definiteness test (defaults: kAuto, 1e-10).
  CholmodFactorConfig factor;
};

/// Empty if valid, else a message naming the bad field. Thread-safe (pure).
std::string validate(const BatchCovarianceSolverConfig& config);

/// Batch mode (beyond the paper): ONE factorisation per compute() call for all its pairs.
///
/// The m distinct keyframes T of the call's valid pairs are constrained last in one CAMD
/// ordering (constraint sets {others} < {T}); CHOLMOD factorises with it (CHOLMOD_GIVEN, no
/// postorder); the trailing dense block L_TT (6m x 6m, read from the supernodes or columns) gives
/// T's marginal information L_TT L_TT^T, whose inverse Sigma_TT = L_TT^-T L_TT^-1 is formed densely
/// once (O(m^3)); each pair's Sigma_{i|j} comes from its 12 x 12 sub-block
/// (conditionalFromCovarianceBlocks). Best when many pairs share few keyframes; m is bounded
/// only by memory (6m x 6m doubles).
class BatchCovarianceSolver final : public ConditionalCovarianceSolver {
 public:
  /// Takes S by value (move it in to avoid a copy). Throws std::invalid_argument if the
  /// config is invalid.
  explicit BatchCovarianceSolver(ReducedCameraMatrix S,
                                 const BatchCovarianceSolverConfig& config = {});
  using ConditionalCovarianceSolver::compute;
  /// One factorisation for all valid pairs (none if there is no valid pair). If it fails,
  /// every valid pair gets its error. Not thread-safe.
  std::vector<ConditionalCovariance> compute(std::span<const KeyframePair> pairs) override;
  /// i alone constrained last: one factorisation.
  ConditionalCovariance marginal(const KeyframePair& pair) override;
  const ReducedCameraMatrix& reducedCameraMatrix() const override { return S_; }

 private:
  // Sigma_TT of the m blocks with constraint[block] = 1, ordered last in one factorisation,
  // and each such block's slot in it (-1 elsewhere). Empty string, or the factorisation's
  // error.
  std::string trailingCovariance(const std::vector<int>& constraint, int m,
                                 Eigen::MatrixXd* sigma_TT, std::vector<int>* slot);

  ReducedCameraMatrix S_;
  BatchCovarianceSolverConfig config_;
  CholmodCommon common_;
  CholmodSymmetricMatrix A_;
};

}  // namespace cblox
