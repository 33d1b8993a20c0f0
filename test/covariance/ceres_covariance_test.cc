#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "core/covariance/batch_covariance_solver.h"
#include "core/covariance/constrained_ordering_solver.h"
#include "core/covariance/kaess_recovery_solver.h"
#include "core/covariance/sparse_solve_solver.h"
#include "test/covariance/ceres_reference.h"
#include "test/covariance/covariance_test_util.h"

namespace cblox {
namespace {

using test::relativeError;

std::string scientific(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.2e", x);
  return buffer;
}

// ceres::Covariance on the same BA problem (same residuals and manifold, fixed keyframe 0
// constant, no loss) gives the same Sigma_{i|j}. Measured: 1e-14 relative (DENSE_SVD and
// SPARSE_QR); asserted 1e-10.
TEST(CeresCovariance, SameConditionalCovarianceAsCeres) {
  test::BaScene scene = test::smallGaugedScene(8, 150, 11);
  scene.problem.keyframes[3].fixed = true;  // a second fixed keyframe: no column either
  const BaLinearization lin = linearizeBundleAdjustment(scene.problem, {});
  const ReducedCameraMatrix S = reduceCameraMatrix(lin);
  ASSERT_EQ(S.numBlocks(), 6);
  const std::vector<KeyframePair> pairs = {
      {101, 102}, {102, 101}, {104, 107}, {107, 105}, {106, 101}};
  test::CeresCovarianceReference ceres_reference(scene.problem, lin);
  ConstrainedOrderingSolver per_pair(S);
  KaessRecoverySolver kaess(S);
  BatchCovarianceSolver batch(S);
  SparseSolveCovarianceSolver sparse(S);
  const auto a = per_pair.compute(pairs);
  const auto b = kaess.compute(pairs);
  const auto c = batch.compute(pairs);
  const auto d = sparse.compute(pairs);
  for (const ceres::CovarianceAlgorithmType algorithm : {ceres::DENSE_SVD, ceres::SPARSE_QR}) {
    const std::vector<ConditionalCovariance> expected = ceres_reference.compute(pairs, algorithm);
    ASSERT_EQ(expected.size(), pairs.size());
    for (size_t p = 0; p < pairs.size(); ++p) {
      ASSERT_TRUE(expected[p].ok && a[p].ok && b[p].ok && c[p].ok && d[p].ok);
      EXPECT_LT(relativeError(a[p].sigma, expected[p].sigma), 1e-10) << p;
      EXPECT_LT(relativeError(b[p].sigma, expected[p].sigma), 1e-10) << p;
      EXPECT_LT(relativeError(c[p].sigma, expected[p].sigma), 1e-10) << p;
      EXPECT_LT(relativeError(d[p].sigma, expected[p].sigma), 1e-10) << p;
      EXPECT_NEAR(d[p].q, expected[p].q, 1e-10 * expected[p].q);
      EXPECT_NEAR(a[p].q, expected[p].q, 1e-10 * expected[p].q);
      RecordProperty(
          "relative_error_" + std::to_string(static_cast<int>(algorithm)) + "_" + std::to_string(p),
          scientific(relativeError(a[p].sigma, expected[p].sigma)));
    }
  }
}

// With the Huber reweighting of the linearization (as the keyframe covariance service uses),
// the reference with Ceres' HuberLoss and apply_loss_function agrees too: observations
// displaced by 10 px lie in Huber's linear region, so the rows are really reweighted.
TEST(CeresCovariance, SameConditionalCovarianceAsCeresWithRobustLoss) {
  test::BaScene scene = test::smallGaugedScene(8, 150, 12);
  for (size_t o = 0; o < scene.problem.observations.size(); o += 7) {
    scene.problem.observations[o].u += 10.0;
  }
  const BaLinearizationConfig robust{true};
  const BaLinearization lin = linearizeBundleAdjustment(scene.problem, {}, robust);
  const BaLinearization plain = linearizeBundleAdjustment(scene.problem, {});
  ASSERT_GT((lin.jacobian - plain.jacobian).norm(), 1e-3 * plain.jacobian.norm());
  const std::vector<KeyframePair> pairs = {{101, 102}, {104, 107}, {107, 105}};
  const auto expected =
      test::CeresCovarianceReference(scene.problem, lin, robust).compute(pairs, ceres::SPARSE_QR);
  const auto got = SparseSolveCovarianceSolver(reduceCameraMatrix(lin)).compute(pairs);
  ASSERT_EQ(expected.size(), pairs.size());
  for (size_t p = 0; p < pairs.size(); ++p) {
    ASSERT_TRUE(expected[p].ok && got[p].ok);
    EXPECT_LT(relativeError(got[p].sigma, expected[p].sigma), 1e-10) << p;
  }
}

}  // namespace
}  // namespace cblox
