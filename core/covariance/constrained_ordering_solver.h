#pragma once

#include <span>
#include <string>
#include <vector>

#include "core/optimization/cholmod_support.h"
#include "core/covariance/conditional_covariance.h"
#include "core/covariance/reduced_camera_matrix.h"

namespace cblox {

struct ConstrainedOrderingSolverConfig {
  /// Factor kind and positive-definiteness test (defaults: kAuto, 1e-10).
  CholmodFactorConfig factor;
};

/// Empty if valid, else a message naming the bad field. Thread-safe (pure).
std::string validate(const ConstrainedOrderingSolverConfig& config);

/// The paper's method: one factorisation PER PAIR with the pair ordered last.
///
/// For pair (i, j): CAMD on S's block pattern with constraint sets {others} < {i} < {j},
/// expanded to scalars and forced through CHOLMOD (CHOLMOD_GIVEN, no postorder), Cholesky
/// P S P^T = L L^T. With L's trailing 12 x 12 block L22 = [[a, 0], [b, c]] (a: keyframe i),
/// the pair's marginal information is L22 L22^T and Sigma_{i|j} = (a a^T)^-1. The trailing
/// block of a supernodal factor is read directly from its supernodes (no conversion to a
/// simplicial factor: reading 12 columns is O(12 * rows of the last supernode), while
/// cholmod_change_factor copies the whole factor: 0.003 ms vs 2.4 ms at 500 keyframes).
/// Per-pair cost: CAMD at block level + CHOLMOD symbolic analysis + numeric factorisation
/// (the analysis cannot be reused across pairs because the permutation differs; what is
/// reused is S in CHOLMOD's layout, its block pattern and the CHOLMOD workspace). The
/// numeric factorisation dominates: it costs a full Cholesky of S (on the two-lap loop
/// scenes of cblox-bench-covariance 2.2 Mflop at 50 keyframes, ~230 Mflop at 500), so for
/// more than a few pairs BatchCovarianceSolver is cheaper.
class ConstrainedOrderingSolver final : public ConditionalCovarianceSolver {
 public:
  /// Takes S by value (move it in to avoid a copy). Throws std::invalid_argument if the
  /// config is invalid.
  explicit ConstrainedOrderingSolver(ReducedCameraMatrix S,
                                     const ConstrainedOrderingSolverConfig& config = {});
  using ConditionalCovarianceSolver::compute;
  /// One factorisation per valid pair. Not thread-safe.
  std::vector<ConditionalCovariance> compute(std::span<const KeyframePair> pairs) override;
  const ReducedCameraMatrix& reducedCameraMatrix() const override { return S_; }
  /// i's block alone ordered last, Sigma = (c c^T)^-1 from the trailing 6x6 block c: one
  /// factorisation.
  ConditionalCovariance marginal(const KeyframePair& pair) override;

 private:
  ConditionalCovariance computePair(const KeyframePair& pair);
  // CAMD with `last` (block indices, in order) after every other block, forced through
  // CHOLMOD; the factor or its error.
  CholmodFactorOutcome factorWithLast(std::initializer_list<int> last);

  ReducedCameraMatrix S_;
  ConstrainedOrderingSolverConfig config_;
  CholmodCommon common_;
  CholmodSymmetricMatrix A_;
};

}  // namespace cblox
