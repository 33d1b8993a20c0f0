#include "core/optimization/ba_linearization.h"

#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>
#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "core/optimization/se3_manifold.h"
#include "test/optimization/numeric_diff.h"
#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

// A small problem: 4 keyframes (keyframe 0 fixed), 30 landmarks, 1 px noise.
test::BaScene smallScene(std::uint32_t seed) {
  test::BaSceneOptions options;
  options.keyframes = 4;
  options.landmarks = 30;
  options.pixel_noise = 1.0;
  options.seed = seed;
  test::BaScene scene = test::makeBaScene(options);
  scene.problem.keyframes[0].fixed = true;
  return scene;
}

// Residual vector of `problem` with keyframe block k perturbed by delta (left) or landmark l
// moved by delta (exactly one of k, l >= 0).
Eigen::VectorXd perturbedResiduals(BundleAdjustmentProblem problem, const BaLinearization& lin,
                                   std::span<const std::uint8_t> outlier, int k, int l,
                                   const Eigen::VectorXd& delta) {
  if (k >= 0) {
    Transformationd& T = problem.keyframes[lin.keyframe_indices[k]].T_C_G;
    T = Transformationd::exp(delta) * T;
  } else {
    problem.landmarks[lin.landmark_indices[l]].p_G += delta;
  }
  return linearizeBundleAdjustment(problem, outlier).residuals;
}

TEST(BaLinearization, ColumnsMatchNumericDerivativesOfTheResiduals) {
  test::BaScene scene = smallScene(801);
  test::perturbInitialState(&scene, 0.01, 0.01, 0.05, 802);  // nonzero residuals
  std::vector<std::uint8_t> outlier(scene.problem.observations.size(), 0);
  outlier[5] = 1;
  const BaLinearization lin = linearizeBundleAdjustment(scene.problem, outlier);
  ASSERT_EQ(lin.keyframe_ids, (std::vector<std::uint64_t>{101, 102, 103}));
  ASSERT_EQ(lin.landmark_ids.size(), 30u);
  EXPECT_EQ(lin.observation_rows[5], -1);
  EXPECT_EQ(lin.jacobian.cols(), 3 * 6 + 30 * 3);
  EXPECT_EQ(lin.jacobian.rows(), lin.residuals.size());
  const Eigen::MatrixXd J = lin.jacobian;
  for (int k = 0; k < 3; ++k) {
    const Eigen::MatrixXd num = test::numericJacobian(
        [&](const Eigen::VectorXd& d) {
          return perturbedResiduals(scene.problem, lin, outlier, k, -1, d);
        },
        Eigen::VectorXd::Zero(6), 1e-7);
    const Eigen::MatrixXd block = J.middleCols(lin.keyframeColumn(k), 6);
    EXPECT_LT((num - block).cwiseAbs().maxCoeff(), 1e-5 * block.cwiseAbs().maxCoeff())
        << "keyframe block " << k;
  }
  for (int l = 0; l < 30; l += 7) {
    const Eigen::MatrixXd num = test::numericJacobian(
        [&](const Eigen::VectorXd& d) {
          return perturbedResiduals(scene.problem, lin, outlier, -1, l, d);
        },
        Eigen::VectorXd::Zero(3), 1e-6);
    const Eigen::MatrixXd block = J.middleCols(lin.landmarkColumn(l), 3);
    EXPECT_LT((num - block).cwiseAbs().maxCoeff(), 1e-5 * block.cwiseAbs().maxCoeff())
        << "landmark block " << l;
  }
}

// The same problem in Ceres: Problem::Evaluate's Jacobian (tangent columns, robust loss
// applied) must equal ours with apply_robust_loss.
TEST(BaLinearization, MatchesCeresProblemEvaluateWithTheHuberLoss) {
  test::BaScene scene = smallScene(811);
  test::perturbInitialState(&scene, 0.02, 0.02, 0.1, 812);  // some residuals beyond Huber
  const BundleAdjustmentProblem& p = scene.problem;
  BaLinearizationConfig config;
  config.apply_robust_loss = true;
  const BaLinearization lin = linearizeBundleAdjustment(p, {}, config);

  std::vector<PoseParameters> poses;
  for (const BaKeyframe& kf : p.keyframes) poses.push_back(toPoseParameters(kf.T_C_G));
  std::vector<Eigen::Vector3d> pts;
  for (const BaLandmark& lm : p.landmarks) pts.push_back(lm.p_G);
  ceres::Problem::Options options;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(options);
  SE3Manifold manifold;
  ceres::HuberLoss huber_stereo(config.huber_delta_stereo), huber_mono(config.huber_delta_mono);
  int beyond_huber = 0;
  for (const BaObservation& o : p.observations) {
    const bool stereo = o.dimension() == 3;
    const double chi2 =
        reprojectionChi2(p.camera, o, p.keyframes[o.keyframe].T_C_G * pts[o.landmark]);
    beyond_huber += chi2 > (stereo ? kChi2Stereo95 : kChi2Mono95);
    problem.AddResidualBlock(newReprojectionCost(p.camera, o), stereo ? &huber_stereo : &huber_mono,
                             poses[o.keyframe].data(), pts[o.landmark].data());
  }
  ASSERT_GT(beyond_huber, 10);
  for (PoseParameters& x : poses) problem.SetManifold(x.data(), &manifold);
  problem.SetParameterBlockConstant(poses[0].data());
  ceres::Problem::EvaluateOptions evaluate;
  for (int k = 1; k < 4; ++k) evaluate.parameter_blocks.push_back(poses[k].data());
  for (Eigen::Vector3d& x : pts) evaluate.parameter_blocks.push_back(x.data());
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  ASSERT_TRUE(problem.Evaluate(evaluate, nullptr, &residuals, nullptr, &crs));
  ASSERT_EQ(crs.num_rows, lin.jacobian.rows());
  ASSERT_EQ(crs.num_cols, lin.jacobian.cols());
  Eigen::MatrixXd ceres_J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int i = crs.rows[r]; i < crs.rows[r + 1]; ++i) ceres_J(r, crs.cols[i]) = crs.values[i];
  }
  const Eigen::MatrixXd ours = lin.jacobian;
  EXPECT_LT((ceres_J - ours).cwiseAbs().maxCoeff(), 1e-9 * ours.cwiseAbs().maxCoeff());
  EXPECT_LT((Eigen::Map<const Eigen::VectorXd>(residuals.data(), residuals.size()) - lin.residuals)
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
}

Eigen::VectorXd eigenvalues(const Eigen::SparseMatrix<double>& H) {
  const Eigen::MatrixXd dense = H;
  EXPECT_EQ((dense - dense.transpose()).cwiseAbs().maxCoeff(), 0.0);  // exactly symmetric
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(dense, Eigen::EigenvaluesOnly)
      .eigenvalues();  // ascending
}

TEST(BaLinearization, InformationIsPositiveDefiniteWithTheGaugeFixed) {
  const test::BaScene scene = smallScene(821);
  const BaLinearization lin = linearizeBundleAdjustment(scene.problem, {});
  const Eigen::SparseMatrix<double> H = informationMatrix(lin);
  ASSERT_EQ(H.rows(), lin.jacobian.cols());
  ASSERT_EQ(H.cols(), lin.jacobian.cols());
  const Eigen::VectorXd ev = eigenvalues(H);
  // Far points make H poorly conditioned (~1e7 here) but clearly regular.
  EXPECT_GT(ev[0], 1e-2);
  // H = J^T J exactly.
  const Eigen::MatrixXd J = lin.jacobian;
  const Eigen::MatrixXd H_dense = H;
  EXPECT_LT((J.transpose() * J - H_dense).cwiseAbs().maxCoeff(),
            1e-9 * H_dense.cwiseAbs().maxCoeff());
}

TEST(BaLinearization, UngaugedInformationHasASixDimensionalNullSpace) {
  test::BaScene scene = smallScene(831);
  scene.problem.keyframes[0].fixed = false;
  // Exact observations at the true state, so the gauge directions are exact null vectors.
  for (BaObservation& o : scene.problem.observations) {
    const Eigen::Vector3d p_C = scene.T_C_G_true[o.keyframe] * scene.p_G_true[o.landmark];
    const StereoCameraModel& c = scene.problem.camera;
    o.u = c.fx * p_C.x() / p_C.z() + c.cx;
    o.v = c.fy * p_C.y() / p_C.z() + c.cy;
    if (o.u_right >= 0) o.u_right = o.u - c.bf / p_C.z();
  }
  const BaLinearization lin = linearizeBundleAdjustment(scene.problem, {});
  EXPECT_EQ(lin.keyframe_ids.size(), 4u);
  const Eigen::VectorXd ev = eigenvalues(informationMatrix(lin));
  const double largest = ev[ev.size() - 1];
  // Six gauge directions (rounding-level eigenvalues); stereo fixes the scale, so the 7th is
  // as large as the smallest one of the gauge-fixed problem.
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(ev[i]), 1e-8 * largest) << "eigenvalue " << i;
  EXPECT_GT(ev[6], 1e-2);
}

TEST(BaLinearization, FromABundleAdjustmentResult) {
  test::BaScene scene = smallScene(841);
  test::perturbInitialState(&scene, 0.01, 0.01, 0.05, 842);
  scene.problem.observations[0].u += 50.0;  // becomes an outlier
  BundleAdjustmentConfig config;
  config.second_pass_iterations = 30;
  config.solver.function_tolerance = config.solver.gradient_tolerance = 1e-16;
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, config);
  ASSERT_EQ(r.outlier[0], 1);
  const BaLinearization lin = linearizeBundleAdjustmentSolution(scene.problem, r);
  EXPECT_EQ(lin.observation_rows[0], -1);
  BundleAdjustmentProblem at_solution = scene.problem;
  for (size_t k = 0; k < r.T_C_G.size(); ++k) at_solution.keyframes[k].T_C_G = r.T_C_G[k];
  for (size_t l = 0; l < r.p_G.size(); ++l) at_solution.landmarks[l].p_G = r.p_G[l];
  const BaLinearization expected = linearizeBundleAdjustment(at_solution, r.outlier);
  EXPECT_EQ(Eigen::MatrixXd(lin.jacobian), Eigen::MatrixXd(expected.jacobian));
  EXPECT_EQ(lin.residuals, expected.residuals);
  // At the solution the gradient J^T r vanishes (the last pass has no robust loss).
  const Eigen::VectorXd gradient = lin.jacobian.transpose() * lin.residuals;
  // (entries of J^T r are ~1e3 away from the optimum: J ~ 1e2..1e3, r ~ 1).
  EXPECT_LT(gradient.cwiseAbs().maxCoeff(), 1e-3);
}

// With 1 px noise, the pose errors of the BA solution against the truth must be distributed
// as the covariance H^-1 predicts: NEES = e^T (H^-1)_pp^-1 e ~ chi-square(54) for 9 free
// keyframes (mean 54, sd 10.4).
TEST(BaLinearization, PredictedCovarianceIsConsistentWithTheActualPoseErrors) {
  test::BaSceneOptions options;
  options.pixel_noise = 1.0;
  options.seed = 861;
  const test::BaScene scene = test::makeGaugedPerturbedBaScene(options, 0.05, 0.02, 0.2);
  BundleAdjustmentConfig config;
  config.second_pass_iterations = 50;
  config.solver.function_tolerance = 1e-14;
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, config);
  const BaLinearization lin = linearizeBundleAdjustmentSolution(scene.problem, r);
  const Eigen::SparseMatrix<double> H = informationMatrix(lin);
  const int P = lin.numPoseColumns();
  ASSERT_EQ(P, 54);
  // Pose covariance = inverse of the Schur complement of the (3x3 block-diagonal) landmarks.
  Eigen::MatrixXd reduced = Eigen::MatrixXd(H.topLeftCorner(P, P));
  for (size_t l = 0; l < lin.landmark_ids.size(); ++l) {
    const int c = lin.landmarkColumn(static_cast<int>(l));
    const Eigen::Matrix3d H_ll = Eigen::MatrixXd(H.block(c, c, 3, 3));
    const Eigen::MatrixXd H_pl = Eigen::MatrixXd(H.block(0, c, P, 3));
    reduced -= H_pl * H_ll.inverse() * H_pl.transpose();
  }
  const Eigen::MatrixXd covariance = reduced.inverse();
  Eigen::VectorXd e(P);
  for (int k = 0; k < P / 6; ++k) {
    const int index = lin.keyframe_indices[k];
    // The tangent convention of the columns: T = exp(e) * T_true.
    e.segment<6>(6 * k) = (r.T_C_G[index] * scene.T_C_G_true[index].inverse()).log();
  }
  const double nees = e.dot(covariance.ldlt().solve(e));
  EXPECT_GT(nees, 25.0);
  EXPECT_LT(nees, 95.0);
}

TEST(BaLinearization, RejectsBadInput) {
  const test::BaScene scene = smallScene(851);
  const std::vector<std::uint8_t> wrong_size(3, 0);
  EXPECT_THROW(linearizeBundleAdjustment(scene.problem, wrong_size), std::invalid_argument);
  const std::vector<std::uint8_t> all(scene.problem.observations.size(), 1);
  try {
    linearizeBundleAdjustment(scene.problem, all);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "linearizeBundleAdjustment: no observation left (all outliers or behind their "
              "cameras)");
  }
  BaLinearizationConfig config;
  EXPECT_EQ(validate(config), "");
  config.huber_delta_mono = 0.0;
  try {
    linearizeBundleAdjustment(scene.problem, {}, config);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "linearizeBundleAdjustment: config: huber deltas must be > 0 and finite");
  }
  BundleAdjustmentProblem empty = scene.problem;
  empty.landmarks.clear();
  EXPECT_THROW(linearizeBundleAdjustment(empty, {}), std::invalid_argument);
  EXPECT_THROW(linearizeBundleAdjustmentSolution(scene.problem, BundleAdjustmentResult{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace cblox
