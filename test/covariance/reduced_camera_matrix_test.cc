#include "core/covariance/reduced_camera_matrix.h"

#include <stdexcept>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "test/covariance/covariance_test_util.h"
#include "test/covariance/loop_scene.h"

namespace cblox {
namespace {

using test::relativeError;

// Dense S = H_pp - H_pl H_ll^-1 H_lp from informationMatrix().
Eigen::MatrixXd denseSchur(const BaLinearization& lin) {
  const Eigen::MatrixXd H(informationMatrix(lin));
  const int P = lin.numPoseColumns();
  const int n = static_cast<int>(H.rows()) - P;
  const Eigen::MatrixXd H_pl = H.topRightCorner(P, n);
  return H.topLeftCorner(P, P) - H_pl * H.bottomRightCorner(n, n).llt().solve(H_pl.transpose());
}

void expectMatchesDenseSchur(const BaLinearization& lin) {
  const ReducedCameraMatrix S = reduceCameraMatrix(lin);
  const Eigen::MatrixXd expected = denseSchur(lin);
  const Eigen::MatrixXd actual(S.matrix);
  ASSERT_EQ(actual.rows(), expected.rows());
  EXPECT_LT(relativeError(actual, expected), 1e-9);
  EXPECT_EQ(actual, actual.transpose());  // exactly symmetric
  EXPECT_TRUE(S.dropped_landmark_ids.empty());
  // Layout: ids in linearization order, lookup, block pattern with every nonzero block.
  EXPECT_EQ(S.keyframe_ids, lin.keyframe_ids);
  const int K = S.numBlocks();
  ASSERT_EQ(static_cast<int>(S.block_col_ptr.size()), K + 1);
  EXPECT_EQ(S.matrix.nonZeros(), 36 * S.block_col_ptr[K]);
  for (int k = 0; k < K; ++k) EXPECT_EQ(S.blockOf(S.keyframe_ids[k]), k);
  EXPECT_EQ(S.blockOf(999999), -1);
  Eigen::MatrixXi stored = Eigen::MatrixXi::Zero(K, K);
  for (int c = 0; c < K; ++c) {
    for (int p = S.block_col_ptr[c]; p < S.block_col_ptr[c + 1]; ++p) {
      if (p > S.block_col_ptr[c]) {
        EXPECT_LT(S.block_row_index[p - 1], S.block_row_index[p]);
      }
      stored(S.block_row_index[p], c) = 1;
    }
  }
  EXPECT_EQ(stored, stored.transpose());
  for (int r = 0; r < K; ++r) {
    for (int c = 0; c < K; ++c) {
      if (!stored(r, c)) {
        EXPECT_EQ((expected.block<6, 6>(6 * r, 6 * c).norm()), 0.0) << r << "," << c;
      }
    }
  }
}

TEST(ReducedCameraMatrix, EqualsDenseSchurComplementOfSmallScene) {
  const test::BaScene scene = test::smallGaugedScene(10, 200, 3);
  const BaLinearization lin = linearizeBundleAdjustment(scene.problem, {});
  ASSERT_EQ(lin.keyframe_ids.size(), 9u);  // keyframe 0 is fixed: no block
  expectMatchesDenseSchur(lin);
}

TEST(ReducedCameraMatrix, EqualsDenseSchurComplementOfLoopScene) {
  test::LoopSceneOptions o;
  o.keyframes = 30;
  o.landmarks_per_keyframe = 20;
  const test::BaScene scene = test::makeLoopBaScene(o);
  const BaLinearization lin = linearizeBundleAdjustment(scene.problem, {});
  expectMatchesDenseSchur(lin);
  // Sparse: not every pair of keyframes is covisible, but the loop links distant ones.
  const ReducedCameraMatrix S = reduceCameraMatrix(lin);
  EXPECT_LT(S.block_col_ptr.back(), 29 * 29 / 2);
  bool loop_edge = false;
  for (int c = 0; c < S.numBlocks(); ++c) {
    for (int p = S.block_col_ptr[c]; p < S.block_col_ptr[c + 1]; ++p) {
      loop_edge = loop_edge || std::abs(S.block_row_index[p] - c) >= 10;
    }
  }
  EXPECT_TRUE(loop_edge);
}

TEST(ReducedCameraMatrix, DropsSingleMonoObservationLandmarkEntirely) {
  const test::BaScene scene = test::smallGaugedScene(6, 80, 4);
  BundleAdjustmentProblem with_extra = scene.problem;
  // A landmark seen once, in mono, by keyframe 3: rank-2 information.
  const Eigen::Vector3d p_G = scene.T_C_G_true[3].inverse() * Eigen::Vector3d(0.3, -0.2, 4.0);
  with_extra.landmarks.push_back(BaLandmark{77777, p_G});
  const Eigen::Vector3d p_C = scene.T_C_G_true[3] * p_G;
  BaObservation obs;
  obs.keyframe = 3;
  obs.landmark = static_cast<int>(with_extra.landmarks.size()) - 1;
  obs.u = 450.0 * p_C.x() / p_C.z() + 376.0;
  obs.v = 450.0 * p_C.y() / p_C.z() + 240.0;
  obs.u_right = -1.0;
  with_extra.observations.push_back(obs);

  const ReducedCameraMatrix S_ref =
      reduceCameraMatrix(linearizeBundleAdjustment(scene.problem, {}));
  const ReducedCameraMatrix S = reduceCameraMatrix(linearizeBundleAdjustment(with_extra, {}));
  EXPECT_EQ(S.dropped_landmark_ids, std::vector<std::uint64_t>{77777});
  EXPECT_EQ(Eigen::MatrixXd(S.matrix), Eigen::MatrixXd(S_ref.matrix));  // as if absent

  // With the rule off (threshold 0) the landmark passes only if its rank-2 block happens to
  // have a positive rounding eigenvalue; either way nothing may crash.
  ReducedCameraMatrixConfig off;
  off.landmark_min_relative_eigenvalue = 0.0;
  EXPECT_NO_THROW(reduceCameraMatrix(linearizeBundleAdjustment(with_extra, {}), off));
}

TEST(ReducedCameraMatrix, RejectsInvalidConfig) {
  ReducedCameraMatrixConfig c;
  EXPECT_EQ(validate(c), "");
  for (const double bad : {-1e-3, 1.0, std::nan("")}) {
    c.landmark_min_relative_eigenvalue = bad;
    EXPECT_NE(validate(c), "");
    const test::BaScene scene = test::smallGaugedScene(3, 20, 5);
    EXPECT_THROW(reduceCameraMatrix(linearizeBundleAdjustment(scene.problem, {}), c),
                 std::invalid_argument);
  }
}

}  // namespace
}  // namespace cblox
