#include "drivers/sim/trajectory_generator.h"

#include <cmath>

#include <gtest/gtest.h>

namespace cblox {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(TrajectoryGeneratorTest, StraightLineRampsUpCruisesAndStops) {
  MotionProfile motion;
  motion.speed_mps = 2.0;
  motion.rate_hz = 100.0;
  motion.accel_time_s = 1.0;
  motion.pitch_down_rad = 0.0;
  motion.start_time_s = 5.0;
  const StampedTrajectory t =
      followPath({Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(10, 0, 1)}, false, 1, motion);
  // Duration: ramps cover v * ramp = 2 m in 2 s, the remaining 8 m take 4 s: 6 s in all.
  ASSERT_EQ(t.size(), 601u);
  EXPECT_DOUBLE_EQ(t.front().timestamp_s, 5.0);
  EXPECT_NEAR(t.back().timestamp_s, 11.0, 1e-9);
  EXPECT_TRUE(t.front().T_G_C.translation().isApprox(Eigen::Vector3d(0, 0, 1), 1e-9));
  EXPECT_NEAR((t.back().T_G_C.translation() - Eigen::Vector3d(10, 0, 1)).norm(), 0.0, 1e-6);
  // Mid-way at cruise speed: 2 m/s.
  const double v = (t[301].T_G_C.translation() - t[300].T_G_C.translation()).norm() * 100.0;
  EXPECT_NEAR(v, 2.0, 1e-6);
  // After the first ramp (1 s): 1 m travelled.
  EXPECT_NEAR(t[100].T_G_C.translation().x(), 1.0, 1e-6);
  // The camera looks along +x with its x axis to the right (-y) and y down (-z).
  const Eigen::Matrix3d R = t[300].T_G_C.rotationMatrix();
  EXPECT_TRUE(R.col(2).isApprox(Eigen::Vector3d(1, 0, 0), 1e-9));
  EXPECT_TRUE(R.col(0).isApprox(Eigen::Vector3d(0, -1, 0), 1e-9));
  EXPECT_TRUE(R.col(1).isApprox(Eigen::Vector3d(0, 0, -1), 1e-9));
}

TEST(TrajectoryGeneratorTest, ClosedLoopReturnsToStartAndIsSmooth) {
  MotionProfile motion;
  motion.speed_mps = 1.0;
  motion.rate_hz = 20.0;
  motion.turn_radius_m = 0.5;
  motion.pitch_down_rad = 0.0;
  const std::vector<Eigen::Vector3d> square = {{0, 0, 1}, {4, 0, 1}, {4, 4, 1}, {0, 4, 1}};
  const StampedTrajectory t = followPath(square, true, 2, motion);
  // Back at the start (the last frame is within one frame period of the stop, at crawl speed).
  EXPECT_LT((t.front().T_G_C.translation() - t.back().T_G_C.translation()).norm(), 1e-4);
  // Two laps of a square with rounded corners: 2 * (16 - 4 * (2 - pi / 2) * 0.5) metres.
  double length = 0.0, max_step = 0.0, max_turn = 0.0;
  for (size_t i = 1; i < t.size(); ++i) {
    const double step = (t[i].T_G_C.translation() - t[i - 1].T_G_C.translation()).norm();
    length += step;
    max_step = std::max(max_step, step);
    max_turn = std::max(max_turn, (t[i - 1].T_G_C.inverse() * t[i].T_G_C).log().tail<3>().norm());
  }
  EXPECT_NEAR(length, 2 * (16.0 - 4 * (2 - kPi / 2) * 0.5), 0.01);
  EXPECT_LE(max_step, 1.0 / 20.0 + 1e-6);  // never faster than cruise
  // Corner of radius 0.5 m at 1 m/s: 2 rad/s, 0.1 rad per frame (plus the smoothing window).
  EXPECT_LT(max_turn, 0.12);
  // Banks into the (left) turns and flies level on the straights.
  double max_roll = 0.0;
  for (const StampedPose& pose : t) {
    const Eigen::Vector3d x = pose.T_G_C.rotationMatrix().col(0);
    max_roll = std::max(max_roll, std::asin(std::clamp(x.z(), -1.0, 1.0)));
  }
  EXPECT_NEAR(max_roll, motion.max_bank_rad, 1e-6);  // left turns raise the right side
}

TEST(TrajectoryGeneratorTest, OrbitLooksAtTheTarget) {
  MotionProfile motion;
  const Eigen::Vector3d target(1, 2, 0);
  const StampedTrajectory t = followPath(orbitWaypoints(Eigen::Vector3d(1, 2, 1.5), 2.0), true, 1,
                                         motion, target);
  for (const StampedPose& pose : t) {
    const Eigen::Vector3d to_target = (target - pose.T_G_C.translation()).normalized();
    EXPECT_TRUE(pose.T_G_C.rotationMatrix().col(2).isApprox(to_target, 1e-9));
    const double r = (pose.T_G_C.translation() - Eigen::Vector3d(1, 2, 1.5)).norm();
    EXPECT_LT(r, 2.0 + 1e-9);
    EXPECT_GT(r, 1.95);  // rounded 48-gon
  }
}

TEST(TrajectoryGeneratorTest, GeneratorsProduceTheirShapes) {
  const auto mower = lawnMowerWaypoints({0, 0}, {10, 4}, 2.0, 2.0);
  ASSERT_EQ(mower.size(), 6u);
  EXPECT_EQ(mower[2], Eigen::Vector3d(10, 2, 2));
  EXPECT_EQ(mower[3], Eigen::Vector3d(0, 2, 2));
  const auto eight = figureEightWaypoints({0, 0, 1}, 4.0, 2.0, 8);
  ASSERT_EQ(eight.size(), 8u);
  EXPECT_NEAR(eight[2].x(), 4.0, 1e-12);  // sin(pi/2)
  EXPECT_NEAR(eight[1].y(), 2.0, 1e-12);  // sin(pi/2) for 2a
  MotionProfile motion;
  EXPECT_GT(followPath(eight, true, 1, motion).size(), 100u);
  EXPECT_GT(followPath(mower, false, 1, motion).size(), 100u);
}

TEST(TrajectoryGeneratorTest, RejectsBadInput) {
  MotionProfile motion;
  EXPECT_THROW(followPath({Eigen::Vector3d::Zero()}, false, 1, motion), std::invalid_argument);
  EXPECT_THROW(followPath({Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, false, 1, motion),
               std::invalid_argument);
  EXPECT_THROW(followPath({Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()}, false, 2, motion),
               std::invalid_argument);
  motion.speed_mps = -1.0;
  EXPECT_THROW(followPath({Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()}, false, 1, motion),
               std::invalid_argument);
  EXPECT_THROW(cameraLookingAlong(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()),
               std::invalid_argument);
}

}  // namespace
}  // namespace cblox
