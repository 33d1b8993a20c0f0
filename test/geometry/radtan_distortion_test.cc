#include "core/geometry/radtan_distortion.h"

#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace cblox {
namespace {

RadTanCoefficients typicalCoefficients() {
  // Roughly a consumer RGB-D colour camera.
  RadTanCoefficients c;
  c.k1 = -0.28;
  c.k2 = 0.07;
  c.p1 = 0.0012;
  c.p2 = -0.0008;
  c.k3 = -0.01;
  return c;
}

TEST(RadTanDistortion, HandComputedValue) {
  // k1 = 0.1, k2 = 0.01, p1 = 0.001, p2 = 0.002, k3 = 0.001 at (0.5, 0.25):
  // r2 = 0.3125, radial = 1 + 0.03125 + 0.0009765625 + 0.000030517578125 = 1.032257080078125
  // x' = 0.5 radial + 2 p1 0.125 + p2 (0.3125 + 0.5)   = 0.5180035400390625 = 848697/1638400
  // y' = 0.25 radial + p1 (0.3125 + 0.125) + 2 p2 0.125 = 0.2590017700195312 = 848697/3276800
  RadTanCoefficients c;
  c.k1 = 0.1;
  c.k2 = 0.01;
  c.p1 = 0.001;
  c.p2 = 0.002;
  c.k3 = 0.001;
  const RadTanDistortion model(c);
  const Eigen::Vector2d xd = model.distort(Eigen::Vector2d(0.5, 0.25));
  EXPECT_NEAR(xd.x(), 848697.0 / 1638400.0, 1e-15);
  EXPECT_NEAR(xd.y(), 848697.0 / 3276800.0, 1e-15);
}

TEST(RadTanDistortion, ZeroCoefficientsAreIdentity) {
  const RadTanDistortion model(RadTanCoefficients{});
  const Eigen::Vector2d x(0.3, -0.7);
  EXPECT_EQ(model.distort(x), x);
  EXPECT_EQ(model.jacobian(x), Eigen::Matrix2d::Identity());
  Eigen::Vector2d xn;
  ASSERT_TRUE(model.undistort(x, &xn));
  EXPECT_EQ(xn, x);
}

TEST(RadTanDistortion, OnlyTangentialTerms) {
  RadTanCoefficients c;
  c.p1 = 0.01;
  c.p2 = -0.02;
  const RadTanDistortion model(c);
  // x = 0.2, y = 0.1: r2 = 0.05, x' = 0.2 + 2*0.01*0.02 - 0.02*(0.05 + 0.08) = 0.1978,
  // y' = 0.1 + 0.01*(0.05 + 0.02) + 2*(-0.02)*0.02 = 0.0999.
  const Eigen::Vector2d xd = model.distort(Eigen::Vector2d(0.2, 0.1));
  EXPECT_NEAR(xd.x(), 0.1978, 1e-15);
  EXPECT_NEAR(xd.y(), 0.0999, 1e-15);
}

TEST(RadTanDistortion, JacobianMatchesCentralDifferences) {
  const RadTanDistortion model(typicalCoefficients());
  const double h = 1e-6;
  for (double x = -0.6; x <= 0.6; x += 0.15) {
    for (double y = -0.45; y <= 0.45; y += 0.15) {
      const Eigen::Vector2d p(x, y);
      Eigen::Matrix2d numeric;
      numeric.col(0) =
          (model.distort(p + Eigen::Vector2d(h, 0)) - model.distort(p - Eigen::Vector2d(h, 0))) /
          (2 * h);
      numeric.col(1) =
          (model.distort(p + Eigen::Vector2d(0, h)) - model.distort(p - Eigen::Vector2d(0, h))) /
          (2 * h);
      EXPECT_LE((model.jacobian(p) - numeric).cwiseAbs().maxCoeff(), 1e-8) << p.transpose();
    }
  }
}

TEST(RadTanDistortion, UndistortRoundTrip) {
  const RadTanDistortion model(typicalCoefficients());
  for (double x = -0.6; x <= 0.6; x += 0.05) {
    for (double y = -0.45; y <= 0.45; y += 0.05) {
      const Eigen::Vector2d xn(x, y);
      Eigen::Vector2d recovered;
      ASSERT_TRUE(model.undistort(model.distort(xn), &recovered)) << xn.transpose();
      EXPECT_LE((recovered - xn).cwiseAbs().maxCoeff(), 1e-10) << xn.transpose();
    }
  }
}

TEST(RadTanDistortion, UndistortReportsNonConvergence) {
  const RadTanDistortion model(typicalCoefficients());
  const Eigen::Vector2d xd = model.distort(Eigen::Vector2d(0.5, 0.4));
  Eigen::Vector2d xn;
  EXPECT_FALSE(model.undistort(xd, &xn, /*max_iterations=*/0));
  EXPECT_FALSE(model.undistort(xd, &xn, /*max_iterations=*/1));
  EXPECT_TRUE(model.undistort(xd, &xn, /*max_iterations=*/20));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(model.undistort(Eigen::Vector2d(nan, 0.1), &xn));
}

TEST(RadTanDistortion, RejectsNonFiniteCoefficients) {
  RadTanCoefficients c = typicalCoefficients();
  c.k2 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(validate(c), "k2 must be finite, got nan");
  EXPECT_THROW(RadTanDistortion{c}, std::invalid_argument);
  EXPECT_EQ(validate(typicalCoefficients()), "");
}

}  // namespace
}  // namespace cblox
