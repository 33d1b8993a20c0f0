#include "core/io/tum_trajectory.h"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

class TumTrajectoryTest : public testing::Test {
 protected:
  test::TempDir dir_{"cblox_tum"};
};

TEST_F(TumTrajectoryTest, RoundTripsPoses) {
  StampedTrajectory trajectory;
  for (int i = 0; i < 5; ++i) {
    Eigen::Matrix<double, 6, 1> xi;
    xi << 0.3 * i, -0.2 * i, 1.0 + i, 0.1 * i, -0.4 + 0.2 * i, 0.7;
    trajectory.push_back({1305031102.175304 + 0.05 * i, Transformationd::exp(xi)});
  }
  std::string error;
  const std::string path = dir_.file("t.txt");
  ASSERT_TRUE(writeTumTrajectory(path, trajectory, &error)) << error;
  const auto read = readTumTrajectory(path, &error);
  ASSERT_TRUE(read.has_value()) << error;
  ASSERT_EQ(read->size(), trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) {
    EXPECT_NEAR((*read)[i].timestamp_s, trajectory[i].timestamp_s, 1e-9);
    EXPECT_TRUE((*read)[i].T_G_C.isApprox(trajectory[i].T_G_C, 1e-9)) << i;
  }
}

TEST_F(TumTrajectoryTest, ParsesTumFileWithCommentsAndScalarLastQuaternion) {
  const std::string path = dir_.write("gt.txt",
                                      "# ground truth trajectory\n"
                                      "# timestamp tx ty tz qx qy qz qw\n"
                                      "\n"
                                      "1.5 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n"
                                      "2.0,4,5,6,0,0,0,1\r\n");
  std::string error;
  const auto read = readTumTrajectory(path, &error);
  ASSERT_TRUE(read.has_value()) << error;
  ASSERT_EQ(read->size(), 2u);
  EXPECT_DOUBLE_EQ((*read)[0].timestamp_s, 1.5);
  EXPECT_EQ((*read)[0].T_G_C.translation(), Eigen::Vector3d(1, 2, 3));
  // 90 degrees about z: x axis goes to y.
  EXPECT_TRUE(((*read)[0].T_G_C.rotation() * Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_EQ((*read)[1].T_G_C.translation(), Eigen::Vector3d(4, 5, 6));
}

TEST_F(TumTrajectoryTest, RejectsBadFilesNamingFileAndLine) {
  struct Case {
    const char* text;
    const char* message;
  };
  const Case cases[] = {
      {"1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0\n", ":2: expected 8 numbers"},
      {"1 0 0 0 0 0 0 1\n2 0 0 x 0 0 0 1\n", ":2: 'x' is not a number"},
      {"1 0 0 0 0 0 0 2\n", ":1: quaternion norm is 2"},
      {"1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", ":2: time 1.000000000 does not increase"},
      {"1 0 0 nan 0 0 0 1\n", ":1: value 'nan' is not finite"},
      {"# only a comment\n", ": no pose"},
  };
  for (const Case& c : cases) {
    const std::string path = dir_.write("bad.txt", c.text);
    std::string error;
    EXPECT_FALSE(readTumTrajectory(path, &error).has_value()) << c.text;
    EXPECT_NE(error.find(path + c.message), std::string::npos) << error;
  }
  std::string error;
  EXPECT_FALSE(readTumTrajectory(dir_.file("missing.txt"), &error).has_value());
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
}

TEST(InterpolatePoseTest, InterpolatesGeodesicallyAndRespectsGapsAndEnds) {
  const Transformationd a(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0));
  const Transformationd b(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())),
                          Eigen::Vector3d(2, 0, 0));
  const StampedTrajectory trajectory = {{10.0, a}, {12.0, b}, {20.0, a}};
  const double inf = std::numeric_limits<double>::infinity();
  const auto mid = interpolatePose(trajectory, 11.0, inf);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(Eigen::AngleAxisd(mid->rotation()).angle(), M_PI / 4, 1e-12);
  EXPECT_TRUE(interpolatePose(trajectory, 12.0, inf)->isApprox(b, 1e-12));
  EXPECT_FALSE(interpolatePose(trajectory, 15.0, 3.0).has_value());  // gap 8 s > 3 s
  EXPECT_TRUE(interpolatePose(trajectory, 11.0, 3.0).has_value());
  EXPECT_FALSE(interpolatePose(trajectory, 9.9, inf).has_value());
  EXPECT_TRUE(interpolatePose(trajectory, 9.9, inf, 0.2)->isApprox(a, 0.0));
  EXPECT_FALSE(interpolatePose({}, 1.0, inf).has_value());
}

}  // namespace
}  // namespace cblox
