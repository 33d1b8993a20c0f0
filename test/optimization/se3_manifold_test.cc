#include "core/optimization/se3_manifold.h"

#include <random>

#include <gtest/gtest.h>

#include "test/optimization/numeric_diff.h"
#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec7 = Eigen::Matrix<double, 7, 1>;

Transformationd randomPose(std::mt19937& rng) {
  return test::perturbPose(Transformationd(), 2.0, 1.0, rng);
}

Vec7 ambient(const Transformationd& T) {
  const PoseParameters p = toPoseParameters(T);
  return Eigen::Map<const Vec7>(p.data());
}

TEST(PoseParameters, LayoutIsQuaternionXyzwThenTranslation) {
  const Transformationd T(Eigen::Quaterniond(0.5, 0.5, -0.5, 0.5), Eigen::Vector3d(1, 2, 3));
  const PoseParameters p = toPoseParameters(T);
  EXPECT_EQ(p, (PoseParameters{0.5, -0.5, 0.5, 0.5, 1, 2, 3}));
  EXPECT_TRUE(fromPoseParameters(p.data()).isApprox(T, 1e-15));
}

TEST(SE3Manifold, PlusIsLeftPerturbationWithTranslationFirstTangent) {
  std::mt19937 rng(3);
  const SE3Manifold m;
  EXPECT_EQ(m.AmbientSize(), 7);
  EXPECT_EQ(m.TangentSize(), 6);
  const Transformationd T = randomPose(rng);
  const Vec7 x = ambient(T);
  Vec6 delta;
  delta << 0.1, -0.2, 0.3, 0.0, 0.0, 0.0;  // pure translation: adds to t
  Vec7 y;
  ASSERT_TRUE(m.Plus(x.data(), delta.data(), y.data()));
  const Transformationd Ty = fromPoseParameters(y.data());
  EXPECT_TRUE(Ty.rotation().isApprox(T.rotation(), 1e-15));
  EXPECT_TRUE(Ty.translation().isApprox(T.translation() + delta.head<3>(), 1e-14));
  delta << 0.0, 0.0, 0.0, 0.0, 0.0, 0.4;  // rotation about z, applied on the left
  ASSERT_TRUE(m.Plus(x.data(), delta.data(), y.data()));
  const Transformationd expected =
      Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ())),
                      Eigen::Vector3d::Zero()) *
      T;
  EXPECT_TRUE(fromPoseParameters(y.data()).isApprox(expected, 1e-14));
}

TEST(SE3Manifold, PlusMinusRoundTrips) {
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 0.7);
  const SE3Manifold m;
  for (int trial = 0; trial < 50; ++trial) {
    const Vec7 x = ambient(randomPose(rng));
    Vec6 delta;
    for (int k = 0; k < 6; ++k) delta[k] = n(rng);
    Vec7 y;
    Vec6 back;
    ASSERT_TRUE(m.Plus(x.data(), delta.data(), y.data()));
    ASSERT_TRUE(m.Minus(y.data(), x.data(), back.data()));
    EXPECT_LT((back - delta).norm(), 1e-12) << "trial " << trial;
    // Plus(x, Minus(z, x)) == z.
    const Vec7 z = ambient(randomPose(rng));
    Vec6 z_minus_x;
    Vec7 z_back;
    ASSERT_TRUE(m.Minus(z.data(), x.data(), z_minus_x.data()));
    ASSERT_TRUE(m.Plus(x.data(), z_minus_x.data(), z_back.data()));
    EXPECT_TRUE(fromPoseParameters(z_back.data()).isApprox(fromPoseParameters(z.data()), 1e-12));
  }
}

TEST(SE3Manifold, PlusAndMinusJacobiansMatchNumericDifferentiation) {
  std::mt19937 rng(5);
  const SE3Manifold m;
  for (int trial = 0; trial < 20; ++trial) {
    const Vec7 x = ambient(randomPose(rng));
    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_jacobian;
    Eigen::Matrix<double, 6, 7, Eigen::RowMajor> minus_jacobian;
    ASSERT_TRUE(m.PlusJacobian(x.data(), plus_jacobian.data()));
    ASSERT_TRUE(m.MinusJacobian(x.data(), minus_jacobian.data()));
    const Eigen::MatrixXd plus_numeric = test::numericJacobian(
        [&](const Eigen::VectorXd& d) {
          Vec7 y;
          m.Plus(x.data(), d.data(), y.data());
          return Eigen::VectorXd(y);
        },
        Eigen::VectorXd::Zero(6), 1e-6);
    EXPECT_LT((plus_numeric - plus_jacobian).cwiseAbs().maxCoeff(), 1e-8) << "trial " << trial;
    const Eigen::MatrixXd minus_numeric = test::numericJacobian(
        [&](const Eigen::VectorXd& y) {
          Vec6 d;
          m.Minus(y.data(), x.data(), d.data());
          return Eigen::VectorXd(d);
        },
        Eigen::VectorXd(x), 1e-6);
    EXPECT_LT((minus_numeric - minus_jacobian).cwiseAbs().maxCoeff(), 1e-7) << "trial " << trial;
    EXPECT_LT(((minus_jacobian * plus_jacobian) - Eigen::Matrix<double, 6, 6>::Identity())
                  .cwiseAbs()
                  .maxCoeff(),
              1e-14);
  }
}

}  // namespace
}  // namespace cblox
