#include "core/geometry/pinhole_camera.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace cblox {
namespace {

PinholeIntrinsics vgaIntrinsics() {
  PinholeIntrinsics in;
  in.fx = 500.0;
  in.fy = 400.0;
  in.cx = 319.5;
  in.cy = 239.5;
  in.width = 640;
  in.height = 480;
  return in;
}

TEST(PinholeIntrinsics, ValidateAcceptsGoodIntrinsics) { EXPECT_EQ(validate(vgaIntrinsics()), ""); }

TEST(PinholeIntrinsics, ValidateNamesTheField) {
  PinholeIntrinsics in = vgaIntrinsics();
  in.fx = -1;
  EXPECT_EQ(validate(in), "fx must be > 0, got -1");
  in = vgaIntrinsics();
  in.fy = 0;
  EXPECT_EQ(validate(in), "fy must be > 0, got 0");
  in = vgaIntrinsics();
  in.fx = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(validate(in).find("fx"), std::string::npos);
  in = vgaIntrinsics();
  in.fy = std::numeric_limits<double>::infinity();
  EXPECT_NE(validate(in).find("fy"), std::string::npos);
  in = vgaIntrinsics();
  in.cx = std::numeric_limits<double>::infinity();
  EXPECT_EQ(validate(in), "cx must be finite, got inf");
  in = vgaIntrinsics();
  in.cy = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(validate(in), "cy must be finite, got nan");
  in = vgaIntrinsics();
  in.width = 0;
  EXPECT_EQ(validate(in), "width must be > 0, got 0");
  in = vgaIntrinsics();
  in.height = -5;
  EXPECT_EQ(validate(in), "height must be > 0, got -5");
}

TEST(PinholeCamera, ConstructorThrowsWithValidateMessage) {
  PinholeIntrinsics in = vgaIntrinsics();
  in.fx = -1;
  try {
    PinholeCamera camera(in);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fx must be > 0, got -1"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(PinholeCamera{vgaIntrinsics()});
}

TEST(PinholeCamera, IntrinsicsAccessor) {
  const PinholeCamera camera(vgaIntrinsics());
  EXPECT_EQ(camera.intrinsics().fx, 500.0);
  EXPECT_EQ(camera.intrinsics().cy, 239.5);
  EXPECT_EQ(camera.intrinsics().width, 640);
  EXPECT_EQ(camera.width(), 640);
  EXPECT_EQ(camera.height(), 480);
}

TEST(PinholeCamera, ProjectKnownPoints) {
  const PinholeCamera camera(vgaIntrinsics());
  Eigen::Vector2d uv;
  ASSERT_TRUE(camera.project(Eigen::Vector3d(0, 0, 2), &uv));
  EXPECT_EQ(uv, Eigen::Vector2d(319.5, 239.5));
  // u = 500 * 0.5 / 2 + 319.5 = 444.5, v = 400 * (-0.25) / 2 + 239.5 = 189.5.
  ASSERT_TRUE(camera.project(Eigen::Vector3d(0.5, -0.25, 2), &uv));
  EXPECT_DOUBLE_EQ(uv.x(), 444.5);
  EXPECT_DOUBLE_EQ(uv.y(), 189.5);
}

TEST(PinholeCamera, ProjectBackProjectRoundTrip) {
  const PinholeCamera camera(vgaIntrinsics());
  // Stay off the u = 0 / v = 0 borders, where rounding may land just outside [0, width).
  for (double u = 0.5; u < 640; u += 37.3) {
    for (double v = 0.5; v < 480; v += 29.1) {
      for (double depth : {0.1, 1.0, 7.5}) {
        const Eigen::Vector2d uv(u, v);
        const Eigen::Vector3d p = camera.backProject(uv, depth);
        EXPECT_EQ(p.z(), depth);
        Eigen::Vector2d uv2;
        ASSERT_TRUE(camera.project(p, &uv2));
        EXPECT_NEAR(uv2.x(), u, 1e-9);
        EXPECT_NEAR(uv2.y(), v, 1e-9);
        const Eigen::Vector3d ray = camera.rayDirection(uv);
        EXPECT_EQ(ray.z(), 1.0);
        EXPECT_NEAR((ray * depth - p).norm(), 0.0, 1e-12);
      }
    }
  }
}

TEST(PinholeCamera, BackProjectAnalytic) {
  const PinholeCamera camera(vgaIntrinsics());
  const Eigen::Vector3d p = camera.backProject(Eigen::Vector2d(419.5, 139.5), 2.0);
  EXPECT_DOUBLE_EQ(p.x(), 100.0 / 500.0 * 2.0);
  EXPECT_DOUBLE_EQ(p.y(), -100.0 / 400.0 * 2.0);
  EXPECT_EQ(p.z(), 2.0);
  const Eigen::Vector3d r = camera.rayDirection(Eigen::Vector2d(419.5, 139.5));
  EXPECT_DOUBLE_EQ(r.x(), 0.2);
  EXPECT_DOUBLE_EQ(r.y(), -0.25);
  EXPECT_EQ(r.z(), 1.0);
}

TEST(PinholeCamera, ProjectRejectsBehindCamera) {
  const PinholeCamera camera(vgaIntrinsics());
  const Eigen::Vector2d sentinel(-7, -7);
  Eigen::Vector2d uv = sentinel;
  EXPECT_FALSE(camera.project(Eigen::Vector3d(0, 0, 0), &uv));
  EXPECT_FALSE(camera.project(Eigen::Vector3d(0, 0, -1), &uv));
  EXPECT_FALSE(camera.project(Eigen::Vector3d(0.01, 0.01, -1e-9), &uv));
  EXPECT_EQ(uv, sentinel);
}

TEST(PinholeCamera, ProjectRejectsOutsideImage) {
  const PinholeCamera camera(vgaIntrinsics());
  Eigen::Vector2d uv;
  // u = 500 * x + 319.5 at z = 1. Accepted range is [0, 640).
  EXPECT_TRUE(camera.project(Eigen::Vector3d(-319.5 / 500, 0, 1), &uv));  // u = 0
  EXPECT_EQ(uv.x(), 0.0);
  EXPECT_FALSE(camera.project(Eigen::Vector3d(-319.6 / 500, 0, 1), &uv));  // u = -0.1
  EXPECT_TRUE(camera.project(Eigen::Vector3d(320.4 / 500, 0, 1), &uv));    // u = 639.9
  EXPECT_FALSE(camera.project(Eigen::Vector3d(320.5 / 500, 0, 1), &uv));   // u = 640
  // v = 400 * y + 239.5. Accepted range is [0, 480).
  EXPECT_FALSE(camera.project(Eigen::Vector3d(0, -239.6 / 400, 1), &uv));
  EXPECT_TRUE(camera.project(Eigen::Vector3d(0, 240.4 / 400, 1), &uv));
  EXPECT_FALSE(camera.project(Eigen::Vector3d(0, 240.5 / 400, 1), &uv));
  // Far outside, and NaN.
  EXPECT_FALSE(camera.project(Eigen::Vector3d(100, 0, 1), &uv));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(camera.project(Eigen::Vector3d(nan, 0, 1), &uv));
  EXPECT_FALSE(camera.project(Eigen::Vector3d(0, 0, nan), &uv));
}

TEST(PinholeCamera, ProjectToPixelRoundsToNearestCentre) {
  const PinholeCamera camera(vgaIntrinsics());
  int u = -1, v = -1;
  ASSERT_TRUE(camera.projectToPixel(Eigen::Vector3d(0, 0, 1), &u, &v));  // (319.5, 239.5)
  EXPECT_EQ(u, 320);
  EXPECT_EQ(v, 240);
  ASSERT_TRUE(camera.projectToPixel(Eigen::Vector3d(-319.9 / 500, 0, 1), &u, &v));  // u = -0.4
  EXPECT_EQ(u, 0);
  EXPECT_FALSE(camera.projectToPixel(Eigen::Vector3d(320.1 / 500, 0, 1), &u, &v));  // u = 639.6
  EXPECT_FALSE(camera.projectToPixel(Eigen::Vector3d(0, 0, -1), &u, &v));
}

TEST(PinholeCamera, FromK) {
  Eigen::Matrix3d K;
  K << 525.0, 0.0, 319.5,  //
      0.0, 523.0, 239.5,   //
      0.0, 0.0, 1.0;
  const PinholeIntrinsics in = PinholeCamera::fromK(K, 640, 480);
  EXPECT_EQ(in.fx, 525.0);
  EXPECT_EQ(in.fy, 523.0);
  EXPECT_EQ(in.cx, 319.5);
  EXPECT_EQ(in.cy, 239.5);
  EXPECT_EQ(in.width, 640);
  EXPECT_EQ(in.height, 480);
  EXPECT_EQ(validate(in), "");

  Eigen::Matrix3d skewed = K;
  skewed(0, 1) = 0.5;
  EXPECT_THROW(PinholeCamera::fromK(skewed, 640, 480), std::invalid_argument);
  Eigen::Matrix3d bad_row = K;
  bad_row(2, 2) = 2.0;
  EXPECT_THROW(PinholeCamera::fromK(bad_row, 640, 480), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
