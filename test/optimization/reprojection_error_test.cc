#include "core/optimization/reprojection_error.h"

#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "core/optimization/se3_manifold.h"
#include "test/optimization/numeric_diff.h"
#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

TEST(StereoCameraModel, ValidateNamesTheBadField) {
  EXPECT_EQ(validate(test::syntheticCamera()), "");
  StereoCameraModel c = test::syntheticCamera();
  c.bf = 0.0;
  EXPECT_EQ(validate(c), "bf must be > 0 and finite, got 0");
  c = test::syntheticCamera();
  c.fx = std::nan("");
  EXPECT_NE(validate(c).find("fx must be > 0"), std::string::npos);
  c = test::syntheticCamera();
  c.cy = HUGE_VAL;
  EXPECT_EQ(validate(c), "cy must be finite");
}

TEST(StereoCameraModel, FromCalibrationUsesFxTimesBaseline) {
  RectifiedStereoCalibration calibration;
  calibration.intrinsics = PinholeIntrinsics{458.0, 457.0, 367.0, 248.0, 752, 480};
  calibration.baseline_m = 0.11;
  const StereoCameraModel c = stereoCameraModelFrom(calibration);
  EXPECT_EQ(c.fx, 458.0);
  EXPECT_EQ(c.fy, 457.0);
  EXPECT_EQ(c.cx, 367.0);
  EXPECT_EQ(c.cy, 248.0);
  EXPECT_DOUBLE_EQ(c.bf, 458.0 * 0.11);
}

TEST(ReprojectionResidual, FollowsTheDocumentedProjection) {
  const StereoCameraModel cam{400.0, 410.0, 300.0, 200.0, 40.0};
  const Eigen::Vector3d p_C(1.0, -0.5, 4.0);
  // u = 400 * 0.25 + 300 = 400, v = 410 * -0.125 + 200 = 148.75, u_right = 400 - 40 / 4 = 390.
  StereoMeasurement m{401.0, 148.0, 392.0, 0.25};
  EXPECT_EQ(m.dimension(), 3);
  double r[3];
  ASSERT_TRUE(weightedReprojectionResidual(cam, m, p_C, r, nullptr));
  EXPECT_DOUBLE_EQ(r[0], 0.5 * (401.0 - 400.0));
  EXPECT_DOUBLE_EQ(r[1], 0.5 * (148.0 - 148.75));
  EXPECT_DOUBLE_EQ(r[2], 0.5 * (392.0 - 390.0));
  EXPECT_DOUBLE_EQ(reprojectionChi2(cam, m, p_C), 0.25 * (1.0 + 0.5625 + 4.0));
  m.u_right = -1.0;  // mono: two residuals
  EXPECT_EQ(m.dimension(), 2);
  EXPECT_DOUBLE_EQ(reprojectionChi2(cam, m, p_C), 0.25 * (1.0 + 0.5625));
  // Behind (or on) the camera plane: no residual, chi2 infinite.
  EXPECT_FALSE(weightedReprojectionResidual(cam, m, Eigen::Vector3d(1, 1, -2), r, nullptr));
  EXPECT_EQ(reprojectionChi2(cam, m, Eigen::Vector3d(1, 1, 0)), HUGE_VAL);
}

TEST(StereoMeasurement, ValidateRejectsNonFiniteAndNonPositiveInformation) {
  EXPECT_EQ(validate(StereoMeasurement{1, 2, -1, 1}), "");
  EXPECT_EQ(validate(StereoMeasurement{std::nan(""), 2, -1, 1}), "u, v and u_right must be finite");
  EXPECT_EQ(validate(StereoMeasurement{1, 2, -1, 0}), "inv_sigma2 must be > 0 and finite");
}

// Residuals of `cost` at a pose block and a point block (the pose quaternion normalised).
Eigen::VectorXd evaluate(const ceres::CostFunction& cost, const double* pose, const double* point) {
  Eigen::VectorXd r(cost.num_residuals());
  const double* parameters[2] = {pose, point};
  EXPECT_TRUE(cost.Evaluate(parameters, r.data(), nullptr));
  return r;
}

void checkCostJacobians(const StereoMeasurement& m, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const StereoCameraModel cam = test::syntheticCamera();
  const Transformationd T_C_G = test::perturbPose(Transformationd(), 0.5, 0.3, rng);
  const Eigen::Vector3d p_G = T_C_G.inverse() * Eigen::Vector3d(0.7, -0.4, 5.0);
  const PoseParameters x = toPoseParameters(T_C_G);
  const std::unique_ptr<ceres::CostFunction> cost(newReprojectionCost(cam, m));
  const int n = m.dimension();
  ASSERT_EQ(cost->num_residuals(), n);

  Eigen::VectorXd r(n);
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J_pose(n, 7);
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> J_point(n, 3);
  const double* parameters[2] = {x.data(), p_G.data()};
  double* jacobians[2] = {J_pose.data(), J_point.data()};
  ASSERT_TRUE(cost->Evaluate(parameters, r.data(), jacobians));

  // Ambient pose Jacobian (the cost normalises the quaternion, so this is exact too).
  const Eigen::MatrixXd num_pose = test::numericJacobian(
      [&](const Eigen::VectorXd& xx) { return evaluate(*cost, xx.data(), p_G.data()); },
      Eigen::Map<const Eigen::VectorXd>(x.data(), 7), 1e-7);
  EXPECT_LT((num_pose - J_pose).cwiseAbs().maxCoeff(), 1e-5 * num_pose.cwiseAbs().maxCoeff());
  const Eigen::MatrixXd num_point = test::numericJacobian(
      [&](const Eigen::VectorXd& p) { return evaluate(*cost, x.data(), p.data()); }, p_G, 1e-6);
  EXPECT_LT((num_point - J_point).cwiseAbs().maxCoeff(), 1e-5 * num_point.cwiseAbs().maxCoeff());

  // Tangent Jacobian as Ceres forms it (ambient * PlusJacobian) against the residual of
  // Plus(x, delta).
  const SE3Manifold manifold;
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_jacobian;
  manifold.PlusJacobian(x.data(), plus_jacobian.data());
  const Eigen::MatrixXd num_tangent = test::numericJacobian(
      [&](const Eigen::VectorXd& delta) {
        PoseParameters y;
        manifold.Plus(x.data(), delta.data(), y.data());
        return evaluate(*cost, y.data(), p_G.data());
      },
      Eigen::VectorXd::Zero(6), 1e-7);
  const Eigen::MatrixXd tangent = J_pose * plus_jacobian;
  EXPECT_LT((num_tangent - tangent).cwiseAbs().maxCoeff(),
            1e-5 * num_tangent.cwiseAbs().maxCoeff());
}

TEST(ReprojectionCost, StereoJacobiansMatchNumericDifferentiation) {
  checkCostJacobians(StereoMeasurement{300.0, 250.0, 290.0, 1.0 / 1.44}, 11);
  checkCostJacobians(StereoMeasurement{500.0, 100.0, 480.0, 1.0}, 12);
}

TEST(ReprojectionCost, MonoJacobiansMatchNumericDifferentiation) {
  checkCostJacobians(StereoMeasurement{300.0, 250.0, -1.0, 1.0}, 13);
  checkCostJacobians(StereoMeasurement{10.0, 400.0, -1.0, 0.48}, 14);
}

TEST(ReprojectionCost, PointBehindTheCameraFailsEvaluation) {
  const StereoCameraModel cam = test::syntheticCamera();
  const std::unique_ptr<ceres::CostFunction> cost(
      newReprojectionCost(cam, StereoMeasurement{300.0, 250.0, 290.0, 1.0}));
  const PoseParameters x = toPoseParameters(Transformationd());
  const Eigen::Vector3d p(0.0, 0.0, -1.0);
  const double* parameters[2] = {x.data(), p.data()};
  double r[3];
  EXPECT_FALSE(cost->Evaluate(parameters, r, nullptr));
}

}  // namespace
}  // namespace cblox
