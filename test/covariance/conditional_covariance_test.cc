#include "core/covariance/conditional_covariance.h"

#include <memory>
#include <stdexcept>
#include <tuple>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "core/covariance/batch_covariance_solver.h"
#include "core/covariance/constrained_ordering_solver.h"
#include "core/covariance/kaess_recovery_solver.h"
#include "core/covariance/sparse_solve_solver.h"
#include "core/optimization/cholmod_support.h"
#include "test/covariance/covariance_test_util.h"
#include "test/covariance/loop_scene.h"

namespace cblox {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using test::loopS;
using test::relativeError;

enum class Method { kPerPair, kKaess, kKaessNoCache, kBatch, kSparseSolve };

struct Variant {
  Method method;
  CholmodFactorKind kind;
};

std::unique_ptr<ConditionalCovarianceSolver> makeSolver(const Variant& v,
                                                        const ReducedCameraMatrix& S) {
  CholmodFactorConfig factor;
  factor.kind = v.kind;
  switch (v.method) {
    case Method::kPerPair:
      return std::make_unique<ConstrainedOrderingSolver>(S,
                                                         ConstrainedOrderingSolverConfig{factor});
    case Method::kKaess:
      return std::make_unique<KaessRecoverySolver>(S, KaessRecoverySolverConfig{factor, true});
    case Method::kKaessNoCache:
      return std::make_unique<KaessRecoverySolver>(S, KaessRecoverySolverConfig{factor, false});
    case Method::kBatch:
      return std::make_unique<BatchCovarianceSolver>(S, BatchCovarianceSolverConfig{factor});
    case Method::kSparseSolve:
      return std::make_unique<SparseSolveCovarianceSolver>(
          S, SparseSolveCovarianceSolverConfig{factor});
  }
  return nullptr;
}

// Every solver with every factor kind.
std::vector<Variant> allVariants() {
  std::vector<Variant> variants;
  for (const Method m : {Method::kPerPair, Method::kKaess, Method::kKaessNoCache, Method::kBatch,
                         Method::kSparseSolve}) {
    for (const CholmodFactorKind kind : {CholmodFactorKind::kAuto, CholmodFactorKind::kSupernodal,
                                         CholmodFactorKind::kSimplicial}) {
      variants.push_back({m, kind});
    }
  }
  return variants;
}

std::string name(const Variant& v) {
  return "method " + std::to_string(static_cast<int>(v.method)) + " kind " +
         std::to_string(static_cast<int>(v.kind));
}

ReducedCameraMatrix smallS(std::uint32_t seed) {
  const test::BaScene scene = test::smallGaugedScene(10, 200, seed);
  return reduceCameraMatrix(linearizeBundleAdjustment(scene.problem, {}));
}

// Sigma_{i|j} straight from the definition on a dense S^-1 (independent of the library's
// helpers): Sigma_ii - Sigma_ij Sigma_jj^-1 Sigma_ji, and q = 1 / lambda_max.
std::pair<Matrix6d, double> definition(const ReducedCameraMatrix& S, const Eigen::MatrixXd& sigma,
                                       const KeyframePair& p) {
  const int a = 6 * S.blockOf(p.i);
  const int b = 6 * S.blockOf(p.j);
  const Matrix6d c = sigma.block<6, 6>(a, a) - sigma.block<6, 6>(a, b) *
                                                   sigma.block<6, 6>(b, b).inverse() *
                                                   sigma.block<6, 6>(b, a);
  return {c, 1.0 / Eigen::SelfAdjointEigenSolver<Matrix6d>(c).eigenvalues()[5]};
}

void expectAllMethodsMatchDense(const ReducedCameraMatrix& S) {
  const std::vector<KeyframePair> pairs = test::allPairs(S);
  const std::vector<ConditionalCovariance> dense = denseConditionalCovariances(S, pairs);
  const Eigen::MatrixXd sigma_all = Eigen::MatrixXd(S.matrix).inverse();
  for (size_t p = 0; p < pairs.size(); ++p) {
    ASSERT_TRUE(dense[p].ok) << dense[p].error;
    const auto [sigma, q] = definition(S, sigma_all, pairs[p]);
    ASSERT_LT(relativeError(dense[p].sigma, sigma), 1e-9);
    ASSERT_NEAR(dense[p].q, q, 1e-9 * q);
  }
  for (const Variant& m : allVariants()) {
    auto solver = makeSolver(m, S);
    const std::vector<ConditionalCovariance> got = solver->compute(pairs);
    ASSERT_EQ(got.size(), pairs.size());
    double worst = 0.0;
    for (size_t p = 0; p < pairs.size(); ++p) {
      ASSERT_TRUE(got[p].ok) << name(m) << ": " << got[p].error;
      EXPECT_EQ(got[p].i, pairs[p].i);
      EXPECT_EQ(got[p].j, pairs[p].j);
      EXPECT_EQ(got[p].error, "");
      worst = std::max(worst, relativeError(got[p].sigma, dense[p].sigma));
      EXPECT_NEAR(got[p].q, dense[p].q, 1e-9 * dense[p].q);
      EXPECT_EQ(got[p].sigma, got[p].sigma.transpose());
    }
    EXPECT_LT(worst, 1e-9) << name(m);
    // Single-pair calls give the same as the batch call.
    const ConditionalCovariance one = solver->compute(pairs[3].i, pairs[3].j);
    ASSERT_TRUE(one.ok);
    EXPECT_LT(relativeError(one.sigma, dense[3].sigma), 1e-9);
  }
}

TEST(ConditionalCovariance, AllMethodsEqualDenseReferenceOnSmallScenes) {
  for (const std::uint32_t seed : {1u, 2u}) expectAllMethodsMatchDense(smallS(seed));
}

TEST(ConditionalCovariance, AllMethodsEqualDenseReferenceOnSparseLoopScene) {
  expectAllMethodsMatchDense(loopS(24));
}

TEST(ConditionalCovariance, ConditioningShrinksTheMarginal) {
  // Sigma_{i|j} <= Sigma_ii (Loewner) and Sigma_{i|j} != Sigma_{j|i}.
  const ReducedCameraMatrix S = smallS(3);
  const Eigen::MatrixXd sigma = Eigen::MatrixXd(S.matrix).inverse();
  ConstrainedOrderingSolver solver(S);
  const ConditionalCovariance ij = solver.compute(S.keyframe_ids[1], S.keyframe_ids[6]);
  const ConditionalCovariance ji = solver.compute(S.keyframe_ids[6], S.keyframe_ids[1]);
  ASSERT_TRUE(ij.ok && ji.ok);
  const Matrix6d diff = sigma.block<6, 6>(6, 6) - ij.sigma;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6d>(diff).eigenvalues()[0],
            -1e-12 * ij.sigma.norm());
  EXPECT_GT(relativeError(ij.sigma, ji.sigma), 1e-3);
}

TEST(KaessRecovery, EveryRecoveredEntryEqualsDenseInverse) {
  const ReducedCameraMatrix S = loopS(16);
  const Eigen::MatrixXd sigma = Eigen::MatrixXd(S.matrix).inverse();
  KaessRecoverySolver solver(S);
  ASSERT_EQ(solver.factorError(), "");
  const int n = static_cast<int>(sigma.rows());
  // Single entries from an empty cache (the recursion alone), in a scattered order.
  for (int r = 0; r < n; r += 7) {
    for (int c = n - 1; c >= 0; c -= 5) {
      solver.clearCache();
      EXPECT_NEAR(solver.covarianceEntry(r, c), sigma(r, c), 1e-9 * sigma.cwiseAbs().maxCoeff());
    }
  }
  // Every entry with the cache filling up.
  solver.clearCache();
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      ASSERT_NEAR(solver.covarianceEntry(r, c), sigma(r, c), 1e-9 * sigma.cwiseAbs().maxCoeff())
          << r << "," << c;
    }
  }
  EXPECT_EQ(solver.cacheSize(), static_cast<size_t>(n * (n + 1) / 2));
  EXPECT_THROW(solver.covarianceEntry(-1, 0), std::out_of_range);
  EXPECT_THROW(solver.covarianceEntry(0, n), std::out_of_range);
}

TEST(KaessRecovery, CacheAcrossPairsKeepsEntriesAndOffClearsThem) {
  const ReducedCameraMatrix S = loopS(16);
  KaessRecoverySolver cached(S);
  KaessRecoverySolver uncached(S, KaessRecoverySolverConfig{{}, false});
  const std::vector<KeyframePair> pairs = {{S.keyframe_ids[2], S.keyframe_ids[9]},
                                           {S.keyframe_ids[4], S.keyframe_ids[12]}};
  const auto a = cached.compute(pairs);
  const auto b = uncached.compute(pairs);
  const size_t after_two = cached.cacheSize();
  EXPECT_EQ(a[1].sigma, b[1].sigma);  // same arithmetic whatever the cache holds
  uncached.compute(std::span<const KeyframePair>(&pairs[0], 1));
  EXPECT_LT(uncached.cacheSize(), after_two);
}

TEST(ConditionalCovariance, FewerObservationsGiveLargerCovarianceAndSmallerQ) {
  // Dropping 3 of every 4 observations of keyframe 5 lowers S (Loewner order), so
  // Sigma_{5|j} can only grow: Sigma_thin - Sigma_full is positive semi-definite, q drops.
  const test::BaScene scene = test::smallGaugedScene(10, 200, 6);
  BundleAdjustmentProblem thin = scene.problem;
  thin.observations.clear();
  int seen = 0;
  for (const BaObservation& o : scene.problem.observations) {
    if (o.keyframe != 5 || seen++ % 4 == 0) thin.observations.push_back(o);
  }
  const ReducedCameraMatrix S_full =
      reduceCameraMatrix(linearizeBundleAdjustment(scene.problem, {}));
  const ReducedCameraMatrix S_thin = reduceCameraMatrix(linearizeBundleAdjustment(thin, {}));
  ConstrainedOrderingSolver full(S_full);
  ConstrainedOrderingSolver sparse(S_thin);
  for (const std::uint64_t j : {101u, 104u, 109u}) {
    const ConditionalCovariance f = full.compute(105, j);
    const ConditionalCovariance t = sparse.compute(105, j);
    ASSERT_TRUE(f.ok && t.ok);
    const Matrix6d diff = t.sigma - f.sigma;
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6d>(diff).eigenvalues()[0],
              -1e-9 * f.sigma.norm());
    EXPECT_LT(t.q, 0.8 * f.q) << "j = " << j;
  }
  // A keyframe far along the path, conditioned on the gauge's neighbour, is less certain
  // than the neighbour's next keyframe (drift grows along the open path).
  EXPECT_LT(full.compute(109, 101).q, full.compute(102, 101).q);
}

TEST(ConditionalCovariance, UngaugedProblemGivesNotPositiveDefiniteForEveryPair) {
  test::BaSceneOptions o;  // no keyframe fixed: 6-dof gauge freedom, S singular
  o.keyframes = 8;
  o.landmarks = 150;
  const test::BaScene scene = test::makeBaScene(o);
  const ReducedCameraMatrix S = reduceCameraMatrix(linearizeBundleAdjustment(scene.problem, {}));
  ASSERT_EQ(S.numBlocks(), 8);
  const std::vector<KeyframePair> pairs = test::allPairs(S);
  for (const Variant& m : allVariants()) {
    const std::vector<ConditionalCovariance> got = makeSolver(m, S)->compute(pairs);
    for (const ConditionalCovariance& r : got) {
      EXPECT_FALSE(r.ok);
      EXPECT_EQ(r.error.rfind(kNotPositiveDefiniteError, 0), 0u) << r.error;
      EXPECT_EQ(r.q, 0.0);
      RecordProperty("error_" + name(m), r.error);
    }
  }
  KaessRecoverySolver kaess(S);
  EXPECT_NE(kaess.factorError(), "");
  EXPECT_THROW(kaess.covarianceEntry(0, 0), std::logic_error);
  SparseSolveCovarianceSolver sparse(S);
  EXPECT_EQ(sparse.factorError().rfind(kNotPositiveDefiniteError, 0), 0u) << sparse.factorError();
  EXPECT_EQ(sparse.factorNonZeros(), 0);
  EXPECT_THROW(sparse.covarianceBlock(S.keyframe_ids[0], S.keyframe_ids[1]), std::logic_error);
}

TEST(ConditionalCovariance, BadIdsArePerPairErrors) {
  const ReducedCameraMatrix S = smallS(1);
  const std::vector<KeyframePair> pairs = {
      {101, 17}, {100, 103}, {104, 104}, {102, 107}, {99999, 99999}};
  for (const Variant& m : allVariants()) {
    const std::vector<ConditionalCovariance> got = makeSolver(m, S)->compute(pairs);
    ASSERT_EQ(got.size(), 5u);
    EXPECT_EQ(got[0].error,
              "keyframe 17 is not in the BA linearization (fixed, culled or unknown)");
    EXPECT_EQ(got[1].error,
              "keyframe 100 is not in the BA linearization (fixed, culled or unknown)");
    EXPECT_EQ(got[2].error, "i and j are the same keyframe (104)");
    EXPECT_TRUE(got[3].ok) << got[3].error;
    EXPECT_EQ(got[4].error,
              "keyframe 99999 is not in the BA linearization (fixed, culled or unknown)");
    for (const int k : {0, 1, 2, 4}) {
      EXPECT_FALSE(got[k].ok);
      EXPECT_EQ(got[k].sigma, Matrix6d::Zero());
    }
    EXPECT_TRUE(makeSolver(m, S)->compute({}).empty());
  }
}

TEST(ConditionalCovariance, InvalidConfigsAreRejected) {
  const ReducedCameraMatrix S = smallS(1);
  for (const double bad : {-1.0, 1.0, std::nan("")}) {
    CholmodFactorConfig f;
    f.min_relative_pivot = bad;
    EXPECT_NE(validate(f), "");
    EXPECT_NE(validate(ConstrainedOrderingSolverConfig{f}), "");
    EXPECT_NE(validate(KaessRecoverySolverConfig{f, true}), "");
    EXPECT_NE(validate(BatchCovarianceSolverConfig{f}), "");
    EXPECT_NE(validate(SparseSolveCovarianceSolverConfig{f}), "");
    EXPECT_THROW(ConstrainedOrderingSolver(S, {f}), std::invalid_argument);
    EXPECT_THROW(KaessRecoverySolver(S, {f, true}), std::invalid_argument);
    EXPECT_THROW(BatchCovarianceSolver(S, {f}), std::invalid_argument);
    EXPECT_THROW(SparseSolveCovarianceSolver(S, {f}), std::invalid_argument);
  }
  CholmodFactorConfig f;
  f.kind = static_cast<CholmodFactorKind>(7);
  EXPECT_EQ(validate(f), "kind must be kAuto, kSupernodal or kSimplicial");
  f = CholmodFactorConfig{};
  for (const double bad : {0.0, -1.0, HUGE_VAL, std::nan("")}) {
    f.auto_supernodal_flops_per_nonzero = bad;
    EXPECT_EQ(validate(f), "auto_supernodal_flops_per_nonzero must be > 0 and finite");
    EXPECT_EQ(validateFactorField(f),
              "factor.auto_supernodal_flops_per_nonzero must be > 0 and finite");
  }
  EXPECT_EQ(validate(CholmodFactorConfig{}), "");
  SparseSolveCovarianceSolverConfig ordering;
  ordering.ordering = static_cast<BlockOrdering>(9);
  EXPECT_EQ(validate(ordering), "ordering is not a BlockOrdering value");
  EXPECT_THROW(SparseSolveCovarianceSolver(S, ordering), std::invalid_argument);
}

TEST(ConditionalCovariance, ForcedPermutationIsKeptAndTrailingBlockMatchesDenseCholesky) {
  // factorizeWithPermutation with a reversed block order: CHOLMOD must keep it, and the
  // trailing block equals the dense Cholesky factor of P S P^T (supernodal and simplicial).
  const ReducedCameraMatrix S = loopS(12);
  const int n = static_cast<int>(S.matrix.rows());
  std::vector<int> perm(n);
  for (int k = 0; k < n; ++k) perm[k] = 6 * (S.numBlocks() - 1 - k / 6) + k % 6;
  Eigen::MatrixXd PSP(n, n);
  const Eigen::MatrixXd dense(S.matrix);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) PSP(r, c) = dense(perm[r], perm[c]);
  }
  const Eigen::MatrixXd L_dense = PSP.llt().matrixL();
  // (kind, kAuto's switch, supernodal expected): kAuto is simplicial here at the default
  // switch (this factor has fewer than 150 flops per nonzero) and supernodal at switch 1.
  const std::tuple<CholmodFactorKind, double, bool> cases[] = {
      {CholmodFactorKind::kSupernodal, 150.0, true},
      {CholmodFactorKind::kSimplicial, 150.0, false},
      {CholmodFactorKind::kAuto, 150.0, false},
      {CholmodFactorKind::kAuto, 1.0, true}};
  for (const auto& [kind, flops_per_nonzero, supernodal] : cases) {
    CholmodCommon common;
    CholmodSymmetricMatrix A(S.matrix);
    CholmodFactorConfig config;
    config.kind = kind;
    config.auto_supernodal_flops_per_nonzero = flops_per_nonzero;
    CholmodFactorOutcome f = factorizeWithPermutation(common, A, perm, config, S.keyframe_ids);
    ASSERT_TRUE(f.ok) << f.error;
    EXPECT_EQ(f.factor.get()->is_super != 0, supernodal);
    EXPECT_LT(common.get()->fl, 150.0 * common.get()->lnz);
    for (const int t : {6, 12, 30}) {
      EXPECT_LT(
          relativeError(trailingFactorBlock(*f.factor.get(), t), L_dense.bottomRightCorner(t, t)),
          1e-12);
    }
    CholmodFactorOutcome bad = factorizeWithPermutation(
        common, A, std::span<const int>(perm).first(6), config, S.keyframe_ids);
    EXPECT_FALSE(bad.ok);
  }
}

TEST(ConditionalCovariance, RelativelyTinyPivotIsNotPositiveDefinite) {
  // Positive definite in exact arithmetic, but the last pivot is 1e-13 of its diagonal
  // entry: rejected by the relative pivot test (CHOLMOD itself accepts it).
  Eigen::MatrixXd dense = Eigen::MatrixXd::Identity(12, 12);
  dense(10, 11) = dense(11, 10) = 0.5;
  dense(11, 11) = 0.25 + 1e-13;  // Schur complement of column 10: 1e-13
  const Eigen::SparseMatrix<double> sparse = dense.sparseView();
  const std::vector<std::uint64_t> ids = {7, 8};
  std::vector<int> perm(12);
  for (int k = 0; k < 12; ++k) perm[k] = k;
  CholmodCommon common;
  CholmodSymmetricMatrix A(sparse);
  CholmodFactorConfig config;
  const CholmodFactorOutcome rejected = factorizeWithPermutation(common, A, perm, config, ids);
  EXPECT_FALSE(rejected.ok);
  EXPECT_EQ(rejected.error.rfind(kNotPositiveDefiniteError, 0), 0u);
  EXPECT_NE(rejected.error.find("relative pivot"), std::string::npos) << rejected.error;
  EXPECT_NE(rejected.error.find("column 11 (keyframe 8)"), std::string::npos) << rejected.error;
  config.min_relative_pivot = 1e-14;
  EXPECT_TRUE(factorizeWithPermutation(common, A, perm, config, ids).ok);
}

}  // namespace
}  // namespace cblox
