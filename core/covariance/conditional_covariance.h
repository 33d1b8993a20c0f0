#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/covariance/reduced_camera_matrix.h"

namespace cblox {

/// Conditional covariance of keyframe pairs from a reduced camera matrix S (issue 6).
///
/// For keyframes i and j (caller ids, free keyframes of the BA linearization), with
/// Sigma = S^-1 the joint covariance of the keyframe tangents,
///   Sigma_{i|j} = Sigma_ii - Sigma_ij Sigma_jj^-1 Sigma_ji,
/// the covariance of keyframe i's tangent delta_i = [rho (m); phi (rad)] (left perturbation
/// of T_C_G, SE3Manifold) given keyframe j's; equivalently the inverse of the ii block of
/// the pair's marginal information. Units: m^2 (top-left 3x3), m*rad (off-diagonal 3x3),
/// rad^2 (bottom-right 3x3). The certainty
///   q = 1 / ||Sigma_{i|j}||_2 = 1 / lambda_max(Sigma_{i|j})
/// mixes m^-2 and rad^-2 (the largest eigenvalue of a matrix with mixed units: in practice
/// dominated by whichever of translation (m^2) and rotation (rad^2) is larger). Note the
/// order: Sigma_{i|j} != Sigma_{j|i} in general.

struct KeyframePair {
  std::uint64_t i = 0;  ///< keyframe whose covariance is wanted
  std::uint64_t j = 0;  ///< keyframe conditioned on
};

/// One pair's result. Errors are per pair, never exceptions: unknown / fixed / culled
/// keyframe, i == j, S not positive definite (ungauged or degenerate problem).
struct ConditionalCovariance {
  std::uint64_t i = 0;
  std::uint64_t j = 0;
  bool ok = false;
  std::string error;                                                        ///< empty iff ok
  Eigen::Matrix<double, 6, 6> sigma = Eigen::Matrix<double, 6, 6>::Zero();  ///< Sigma_{i|j}
  double q = 0.0;  ///< 1 / lambda_max(sigma), 0 unless ok
};

/// The common interface of the solvers (constrained_ordering_solver.h,
/// kaess_recovery_solver.h, batch_covariance_solver.h). Implementations own CHOLMOD
/// workspace: not thread-safe; use one object per thread.
class ConditionalCovarianceSolver {
 public:
  virtual ~ConditionalCovarianceSolver() = default;
  /// One result per pair, in order. Not thread-safe.
  virtual std::vector<ConditionalCovariance> compute(std::span<const KeyframePair> pairs) = 0;
  /// compute() of one pair. Not thread-safe.
  ConditionalCovariance compute(std::uint64_t i, std::uint64_t j) {
    const KeyframePair pair{i, j};
    return compute(std::span<const KeyframePair>(&pair, 1)).front();
  }
  /// The marginal covariance [S^-1]_ii of keyframe pair.i: its answer given a keyframe the
  /// BA holds fixed (pair.j names it in the result; it has no block in S, which is already
  /// conditioned on it). Errors: pair.i without a block (marginalIdError), a failed
  /// factorisation. Not thread-safe.
  virtual ConditionalCovariance marginal(const KeyframePair& pair) = 0;
  /// The reduced camera matrix the solver answers from (its own copy). Thread-safe (const).
  virtual const ReducedCameraMatrix& reducedCameraMatrix() const = 0;
};

/// `config` if validate(config) is empty, else throws std::invalid_argument("<who>: config:
/// <message>"). For the solvers' constructors. Thread-safe (pure).
template <typename Config>
const Config& validatedConfig(const Config& config, const char* who) {
  if (const std::string e = validate(config); !e.empty()) {
    throw std::invalid_argument(std::string(who) + ": config: " + e);
  }
  return config;
}

/// The per-pair errors on ids: "keyframe 17 is not in the BA linearization (fixed, culled
/// or unknown)" or "i and j are the same keyframe (17)"; empty if both ids have blocks in
/// S and differ. Thread-safe (pure).
std::string pairIdError(const ReducedCameraMatrix& S, const KeyframePair& pair);

/// marginal()'s id error: pairIdError's message for pair.i if it has no block in S, else
/// empty (pair.j is not looked up). Thread-safe (pure).
std::string marginalIdError(const ReducedCameraMatrix& S, const KeyframePair& pair);

/// A failed result for `pair` with `error`. Thread-safe (pure).
ConditionalCovariance failedPair(const KeyframePair& pair, std::string error);

/// The loop of the solvers that factorise once: per pair, pairIdError's message if the ids are
/// bad, else `factor_error` if the factorisation failed (non-empty), else compute(pair).
/// Thread-safe if compute is.
template <typename Compute>
std::vector<ConditionalCovariance> computeValidPairs(const ReducedCameraMatrix& S,
                                                     std::span<const KeyframePair> pairs,
                                                     const std::string& factor_error,
                                                     Compute&& compute) {
  std::vector<ConditionalCovariance> out;
  out.reserve(pairs.size());
  for (const KeyframePair& pair : pairs) {
    if (std::string e = pairIdError(S, pair); !e.empty()) {
      out.push_back(failedPair(pair, std::move(e)));
    } else if (!factor_error.empty()) {
      out.push_back(failedPair(pair, factor_error));
    } else {
      out.push_back(compute(pair));
    }
  }
  return out;
}

/// The result from the lower-triangular 6x6 factor block `a` of keyframe i when the pair's
/// marginal information is factored with i before j: Sigma_{i|j} = (a a^T)^-1 (computed as
/// a^-T a^-1, symmetrised), q from its largest eigenvalue. Thread-safe (pure).
ConditionalCovariance conditionalFromFactorBlock(const KeyframePair& pair,
                                                 const Eigen::Matrix<double, 6, 6>& a);

/// The result from the joint covariance blocks Sigma_ii, Sigma_ij, Sigma_jj (Sigma_jj must
/// be positive definite; fails with an error otherwise). Thread-safe (pure).
ConditionalCovariance conditionalFromCovarianceBlocks(const KeyframePair& pair,
                                                      const Eigen::Matrix<double, 6, 6>& ii,
                                                      const Eigen::Matrix<double, 6, 6>& ij,
                                                      const Eigen::Matrix<double, 6, 6>& jj);

/// The result for pair.i given a keyframe held fixed (pair.j): Sigma_{i|j} = Sigma_ii, the
/// marginal covariance (symmetrised, q from its largest eigenvalue). Thread-safe (pure).
ConditionalCovariance conditionalGivenFixed(const KeyframePair& pair,
                                            const Eigen::Matrix<double, 6, 6>& ii);

/// 1 / lambda_max(sigma) for a symmetric positive definite sigma. Thread-safe (pure).
double certaintyOf(const Eigen::Matrix<double, 6, 6>& sigma);

/// Dense reference for small problems (K up to a few hundred): Sigma = S^-1 by dense
/// Cholesky (LLT), then conditionalFromCovarianceBlocks per pair. S not positive definite
/// gives every valid pair the kNotPositiveDefiniteError message. Thread-safe (pure).
std::vector<ConditionalCovariance> denseConditionalCovariances(const ReducedCameraMatrix& S,
                                                               std::span<const KeyframePair> pairs);

}  // namespace cblox
