#include "core/covariance/sparse_solve_solver.h"

#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test/covariance/covariance_test_util.h"

namespace cblox {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using test::loopS;
using test::relativeError;

// A reduced camera matrix made by hand from a dense symmetric positive definite matrix and
// the block pattern `adjacent(r, c)` (true on the diagonal), keyframe ids 10, 11, ...
template <typename Adjacent>
ReducedCameraMatrix handMadeS(int K, Adjacent adjacent, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(6 * K, 6 * K);
  for (int c = 0; c < K; ++c) {
    for (int r = c + 1; r < K; ++r) {
      if (!adjacent(r, c)) continue;
      // An "edge" term J^T J with J = [A, -I] keeps the sum positive semi-definite.
      Matrix6d a;
      for (int e = 0; e < 36; ++e) a(e) = normal(rng);
      dense.block<6, 6>(6 * c, 6 * c) += a.transpose() * a;
      dense.block<6, 6>(6 * c, 6 * r) -= a.transpose();
      dense.block<6, 6>(6 * r, 6 * c) -= a;
      dense.block<6, 6>(6 * r, 6 * r) += Matrix6d::Identity();
    }
    dense.block<6, 6>(6 * c, 6 * c) += 0.5 * Matrix6d::Identity();  // the prior: a gauge
  }
  ReducedCameraMatrix S;
  // Keep every entry of the stored blocks (even exact zeros) as reduceCameraMatrix does.
  S.matrix.resize(6 * K, 6 * K);
  std::vector<Eigen::Triplet<double>> triplets;
  S.block_col_ptr.push_back(0);
  for (int c = 0; c < K; ++c) {
    for (int r = 0; r < K; ++r) {
      if (r != c && !adjacent(std::max(r, c), std::min(r, c))) continue;
      S.block_row_index.push_back(r);
      for (int e = 0; e < 36; ++e) {
        triplets.emplace_back(6 * r + e % 6, 6 * c + e / 6, dense(6 * r + e % 6, 6 * c + e / 6));
      }
    }
    S.block_col_ptr.push_back(static_cast<int>(S.block_row_index.size()));
    S.keyframe_ids.push_back(10 + c);
    S.block_of_id[10 + c] = c;
  }
  S.matrix.setFromTriplets(triplets.begin(), triplets.end());
  S.matrix.makeCompressed();
  return S;
}

TEST(SparseSolve, EveryCovarianceBlockEqualsDenseInverse) {
  const ReducedCameraMatrix S = loopS(16);
  const Eigen::MatrixXd sigma = Eigen::MatrixXd(S.matrix).inverse();
  const double scale = sigma.cwiseAbs().maxCoeff();
  struct Case {
    CholmodFactorKind kind;
    BlockOrdering ordering;
    bool vectorized;  // the AVX2 kernel where the CPU has it, else the portable one
  };
  for (const Case& c :
       {Case{CholmodFactorKind::kSupernodal, BlockOrdering::kNestedDissection, true},
        Case{CholmodFactorKind::kSimplicial, BlockOrdering::kNestedDissection, true},
        Case{CholmodFactorKind::kSupernodal, BlockOrdering::kAmd, true},
        Case{CholmodFactorKind::kSupernodal, BlockOrdering::kNestedDissection, false}}) {
    SCOPED_TRACE(std::string(blockOrderingName(c.ordering)) +
                 (c.vectorized ? " vectorized" : " portable"));
    CholmodFactorConfig factor;
    factor.kind = c.kind;
    SparseSolveCovarianceSolver solver(S, {factor, c.ordering, c.vectorized});
    ASSERT_EQ(solver.factorError(), "");
    EXPECT_GT(solver.factorNonZeros(), S.matrix.nonZeros() / 2);
    for (int a = 0; a < S.numBlocks(); ++a) {
      for (int b = 0; b < S.numBlocks(); ++b) {
        const Matrix6d block = solver.covarianceBlock(S.keyframe_ids[a], S.keyframe_ids[b]);
        ASSERT_LT((block - sigma.block<6, 6>(6 * a, 6 * b)).cwiseAbs().maxCoeff(), 1e-9 * scale)
            << a << "," << b;
      }
    }
    EXPECT_THROW(solver.covarianceBlock(S.keyframe_ids[0], 7), std::invalid_argument);
  }
}

// Given a keyframe held fixed (no block: the gauge), the answer is the marginal [S^-1]_ii.
TEST(SparseSolve, MarginalGivenTheGaugeEqualsTheDenseInverseDiagonalBlock) {
  const ReducedCameraMatrix S = loopS(12);
  const Eigen::MatrixXd sigma = Eigen::MatrixXd(S.matrix).inverse();
  SparseSolveCovarianceSolver solver(S);
  const std::uint64_t gauge = 9999;  // no block in S
  ASSERT_LT(S.blockOf(gauge), 0);
  for (int b = 0; b < S.numBlocks(); ++b) {
    const ConditionalCovariance r = solver.marginal({S.keyframe_ids[b], gauge});
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_EQ(r.i, S.keyframe_ids[b]);
    EXPECT_EQ(r.j, gauge);
    EXPECT_LT(relativeError(r.sigma, sigma.block<6, 6>(6 * b, 6 * b)), 1e-9) << b;
    EXPECT_NEAR(r.q, certaintyOf(r.sigma), 1e-12 * r.q);
  }
  const ConditionalCovariance unknown = solver.marginal({gauge, S.keyframe_ids[0]});
  EXPECT_FALSE(unknown.ok);
  EXPECT_NE(unknown.error.find("9999"), std::string::npos) << unknown.error;
}

TEST(SparseSolve, EachKeyframeIsSolvedOncePerCallOnItsEtreeReach) {
  const ReducedCameraMatrix S = loopS(24);
  const int n = static_cast<int>(S.matrix.rows());
  SparseSolveCovarianceSolver solver(S);
  const std::uint64_t a = S.keyframe_ids[2], b = S.keyframe_ids[5], c = S.keyframe_ids[11];
  const std::vector<KeyframePair> pairs = {{a, b}, {b, a}, {a, c}, {c, b}, {a, b}};
  const std::vector<ConditionalCovariance> got = solver.compute(pairs);
  for (const ConditionalCovariance& r : got) ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(got[0].sigma, got[4].sigma);
  const SparseSolveStats first = solver.stats();
  EXPECT_EQ(first.keyframes_solved, 3);  // a, b, c: once each
  // Each reach holds the keyframe's own 6 columns and the etree root, not all of L.
  EXPECT_GE(first.reached_columns, 3 * 6 + 1);
  EXPECT_LT(first.reached_columns, 3 * n);
  EXPECT_GE(first.flops, 12.0 * static_cast<double>(first.reached_columns));
  // The next call starts from an empty cache and counts afresh.
  solver.compute(std::span<const KeyframePair>(pairs).first(1));
  EXPECT_EQ(solver.stats().keyframes_solved, 2);
  EXPECT_LT(solver.stats().flops, first.flops);
}

// Nested dissection cuts the loop into halves, quarters, ...: every keyframe's path to the
// root crosses one separator per level instead of running along the band as AMD's chains do.
// The answers are the same (the ordering only changes the order of exact arithmetic). At 320
// keyframes: 0.70x the columns and 0.65x the flops of AMD (1.9x fewer flops at 500 keyframes
// with 50 landmarks each, BENCHMARKS.md).
TEST(SparseSolve, NestedDissectionReachesFewerColumnsThanAmdOnALoop) {
  const ReducedCameraMatrix S = loopS(320);
  std::vector<KeyframePair> pairs;  // every keyframe solved once
  for (int b = 0; b + 1 < S.numBlocks(); b += 2) {
    pairs.push_back({S.keyframe_ids[b], S.keyframe_ids[b + 1]});
  }
  SparseSolveCovarianceSolver amd(S, {CholmodFactorConfig{}, BlockOrdering::kAmd});
  SparseSolveCovarianceSolver nd(S, {CholmodFactorConfig{}, BlockOrdering::kNestedDissection});
  const std::vector<ConditionalCovariance> by_amd = amd.compute(pairs);
  const std::vector<ConditionalCovariance> by_nd = nd.compute(pairs);
  for (size_t p = 0; p < pairs.size(); ++p) {
    ASSERT_TRUE(by_amd[p].ok && by_nd[p].ok) << by_amd[p].error << by_nd[p].error;
    EXPECT_LT(relativeError(by_nd[p].sigma, by_amd[p].sigma), 1e-9) << p;
  }
  EXPECT_EQ(nd.stats().keyframes_solved, 318);  // 319 blocks: all but the last
  // The portable kernel gives the same answers up to rounding (FMA's single rounding).
  SparseSolveCovarianceSolver portable(
      S, {CholmodFactorConfig{}, BlockOrdering::kNestedDissection, /*vectorized=*/false});
  const std::vector<ConditionalCovariance> by_portable = portable.compute(pairs);
  for (size_t p = 0; p < pairs.size(); ++p) {
    ASSERT_TRUE(by_portable[p].ok) << by_portable[p].error;
    EXPECT_LT(relativeError(by_portable[p].sigma, by_nd[p].sigma), 1e-12) << p;
  }
  EXPECT_EQ(portable.stats().flops, nd.stats().flops);
  EXPECT_LT(nd.stats().reached_columns, amd.stats().reached_columns * 3 / 4);
  EXPECT_LT(nd.stats().flops, amd.stats().flops * 3 / 4);
}

// compute() solves all the keyframes its pairs need in shared sweeps of L (16 at a time);
// each keyframe's arithmetic is the same as alone, in the same order, so the answers are
// bit-identical to one pair per call.
TEST(SparseSolve, KeyframesSolvedTogetherEqualOnePairPerCall) {
  const ReducedCameraMatrix S = loopS(60);
  std::vector<KeyframePair> pairs;  // 40 distinct keyframes: three sweeps (16, 16, 8)
  for (int b = 0; b < 40; b += 2) {
    pairs.push_back({S.keyframe_ids[b], S.keyframe_ids[(b * 7 + 1) % 40]});
  }
  pairs.push_back(pairs[3]);                     // a repeat
  pairs.push_back({S.keyframe_ids[4], 424242});  // an unknown id: a per-pair error
  for (const bool vectorized : {true, false}) {
    SCOPED_TRACE(vectorized);
    SparseSolveCovarianceSolver solver(
        S, {CholmodFactorConfig{}, BlockOrdering::kNestedDissection, vectorized});
    const std::vector<ConditionalCovariance> together = solver.compute(pairs);
    EXPECT_EQ(solver.stats().keyframes_solved, 40);
    ASSERT_EQ(together.size(), pairs.size());
    for (size_t p = 0; p + 1 < pairs.size(); ++p) {
      const ConditionalCovariance alone = solver.compute(pairs[p].i, pairs[p].j);
      ASSERT_TRUE(together[p].ok && alone.ok) << together[p].error << alone.error;
      EXPECT_EQ(together[p].sigma, alone.sigma) << p;
      EXPECT_EQ(together[p].q, alone.q) << p;
    }
    EXPECT_FALSE(together.back().ok);
    EXPECT_NE(together.back().error.find("424242"), std::string::npos) << together.back().error;
  }
}

TEST(SparseSolve, DisconnectedComponentsGiveZeroCrossCovariance) {
  // Keyframes 0-1-2 form a chain, 3-4 another one: L's etree is a forest; the cross
  // covariance between the components is exactly zero, so Sigma_{i|j} = Sigma_ii there.
  const auto adjacent = [](int r, int c) {
    return r == c || (r == c + 1 && r != 3);  // edges 1-0, 2-1, 4-3
  };
  const ReducedCameraMatrix S = handMadeS(5, adjacent, 3);
  const Eigen::MatrixXd sigma = Eigen::MatrixXd(S.matrix).inverse();
  SparseSolveCovarianceSolver solver(S);
  ASSERT_EQ(solver.factorError(), "");
  EXPECT_EQ(solver.covarianceBlock(10, 14), Matrix6d::Zero());
  EXPECT_NE(solver.covarianceBlock(10, 12), Matrix6d::Zero());
  const std::vector<KeyframePair> pairs = test::allPairs(S);
  const std::vector<ConditionalCovariance> got = solver.compute(pairs);
  const std::vector<ConditionalCovariance> dense = denseConditionalCovariances(S, pairs);
  for (size_t p = 0; p < pairs.size(); ++p) {
    ASSERT_TRUE(got[p].ok && dense[p].ok) << got[p].error;
    EXPECT_LT(relativeError(got[p].sigma, dense[p].sigma), 1e-9) << p;
  }
  const ConditionalCovariance across = solver.compute(11, 13);
  ASSERT_TRUE(across.ok);
  EXPECT_LT(relativeError(across.sigma, Matrix6d(sigma.block<6, 6>(6, 6))), 1e-9);
}

}  // namespace
}  // namespace cblox
