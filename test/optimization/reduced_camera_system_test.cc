// The reduced camera systems of schur_lm.h: the block-sparse one (CHOLMOD) solves the same
// systems as the dense one (Eigen's LLT) and as a direct dense solve of the full matrix.

#include "core/optimization/reduced_camera_system.h"

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

namespace cblox {
namespace {

// A banded block pattern with a few long-range blocks (a loop): blocks (r, c) with c - r <= 2,
// and (0, n - 1), (1, n - 2).
std::vector<std::vector<int>> loopPattern(int n) {
  std::vector<std::vector<int>> rows(static_cast<size_t>(n));
  for (int c = 0; c < n; ++c) {
    std::vector<int>& column = rows[static_cast<size_t>(c)];
    for (int r = std::max(0, c - 2); r <= c; ++r) column.push_back(r);
    if (c == n - 1) column.push_back(0);
    if (c == n - 2 && c >= 1) column.push_back(1);
    std::sort(column.begin(), column.end());
    column.erase(std::unique(column.begin(), column.end()), column.end());
  }
  return rows;
}

// A random symmetric positive definite matrix with that block pattern: sum of J^T J over
// random 6 x 12 "measurements" of each pattern pair, plus the identity.
Eigen::MatrixXd randomSpd(int n, const std::vector<std::vector<int>>& rows, std::mt19937* rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd S = Eigen::MatrixXd::Identity(6 * n, 6 * n);
  for (int c = 0; c < n; ++c) {
    for (const int r : rows[static_cast<size_t>(c)]) {
      Eigen::Matrix<double, 6, 12> J;
      for (int i = 0; i < J.size(); ++i) J.data()[i] = normal(*rng);
      Eigen::VectorXi index(12);
      for (int i = 0; i < 6; ++i) index[i] = 6 * r + i, index[6 + i] = 6 * c + i;
      const Eigen::Matrix<double, 12, 12> H = J.transpose() * J;
      for (int i = 0; i < 12; ++i) {
        for (int j = 0; j < 12; ++j) S(index[i], index[j]) += H(i, j);
      }
    }
  }
  return S;
}

template <class System>
void fill(System* system, const Eigen::MatrixXd& S, const std::vector<std::vector<int>>& rows) {
  system->setZero();
  for (int c = 0; c < static_cast<int>(rows.size()); ++c) {
    for (const int r : rows[static_cast<size_t>(c)]) {
      system->block(r, c) = S.block<6, 6>(6 * r, 6 * c);
    }
  }
}

TEST(ReducedCameraSystemTest, SparseAndDenseSolveTheSameSystem) {
  std::mt19937 rng(5);
  for (const int n : {1, 2, 7, 40}) {
    const std::vector<std::vector<int>> rows = loopPattern(n);
    const Eigen::MatrixXd S = randomSpd(n, rows, &rng);
    Eigen::VectorXd b(6 * n);
    for (int i = 0; i < b.size(); ++i) b[i] = std::normal_distribution<double>(0.0, 1.0)(rng);
    const Eigen::VectorXd expected = S.ldlt().solve(b);

    SparseReducedCameraSystem sparse(n, rows);
    DenseReducedCameraSystem dense(n, rows);
    // Twice: the second solve reuses the symbolic factorisation of the first.
    for (int round = 0; round < 2; ++round) {
      fill(&sparse, round == 0 ? S : Eigen::MatrixXd(2.0 * S), rows);
      fill(&dense, round == 0 ? S : Eigen::MatrixXd(2.0 * S), rows);
      const Eigen::VectorXd want = round == 0 ? expected : Eigen::VectorXd(0.5 * expected);
      Eigen::VectorXd x_sparse, x_dense;
      ASSERT_TRUE(sparse.solve(b, &x_sparse)) << n;
      ASSERT_TRUE(dense.solve(b, &x_dense)) << n;
      EXPECT_LT((x_sparse - want).norm(), 1e-10 * want.norm()) << n;
      EXPECT_LT((x_dense - want).norm(), 1e-10 * want.norm()) << n;
    }
    int blocks = 0;
    for (const auto& r : rows) blocks += static_cast<int>(r.size());
    EXPECT_EQ(sparse.numBlocks(), blocks);
  }
}

TEST(ReducedCameraSystemTest, NotPositiveDefiniteIsReported) {
  const std::vector<std::vector<int>> rows = loopPattern(5);
  std::mt19937 rng(6);
  Eigen::MatrixXd S = randomSpd(5, rows, &rng);
  S(13, 13) = -1.0;  // a negative pivot
  SparseReducedCameraSystem sparse(5, rows);
  DenseReducedCameraSystem dense(5, rows);
  fill(&sparse, S, rows);
  fill(&dense, S, rows);
  Eigen::VectorXd x;
  EXPECT_FALSE(sparse.solve(Eigen::VectorXd::Ones(30), &x));
  EXPECT_FALSE(dense.solve(Eigen::VectorXd::Ones(30), &x));
}

TEST(ReducedCameraSystemTest, MalformedPatternsAreRejected) {
  EXPECT_THROW(SparseReducedCameraSystem(0, {}), std::invalid_argument);
  EXPECT_THROW(SparseReducedCameraSystem(2, {{0}}), std::invalid_argument);        // 1 column
  EXPECT_THROW(SparseReducedCameraSystem(2, {{0}, {0}}), std::invalid_argument);   // no diagonal
  EXPECT_THROW(SparseReducedCameraSystem(2, {{0}, {1, 0}}), std::invalid_argument);  // order
  EXPECT_THROW(SparseReducedCameraSystem(2, {{0}, {0, 0, 1}}), std::invalid_argument);
  EXPECT_NO_THROW(SparseReducedCameraSystem(2, {{0}, {0, 1}}));
}

}  // namespace
}  // namespace cblox
