#include "drivers/synthetic/synthetic_frame_source.h"

#include <gtest/gtest.h>

#include "drivers/synthetic/scenes.h"

namespace cblox {
namespace {

using Eigen::Vector3d;

PinholeIntrinsics smallIntrinsics() {
  PinholeIntrinsics in;
  in.fx = in.fy = 100.0;
  in.cx = 40.0;
  in.cy = 30.0;
  in.width = 80;
  in.height = 60;
  return in;
}

TEST(SyntheticDepthSourceTest, DeliversEveryPoseThenStops) {
  const std::vector<Transformationd> trajectory =
      makeOrbitTrajectory(Vector3d(0, 0, 1.5), 1.5, 0.0, 5, Vector3d(0.5, 0, 1.0));
  SyntheticDepthSource source(makeDemoRoom(), smallIntrinsics(), trajectory, 30.0, 10.0);
  ASSERT_EQ(source.size(), 5u);
  const AnalyticScene reference = makeDemoRoom();
  SyntheticFrame frame;
  for (size_t i = 0; i < trajectory.size(); ++i) {
    ASSERT_TRUE(source.next(&frame));
    EXPECT_EQ(frame.timestamp_ns, std::llround(static_cast<double>(i) * 1e9 / 30.0));
    EXPECT_TRUE(frame.T_G_C.isApprox(trajectory[i], 1e-12));
    ASSERT_EQ(frame.depth.width, 80);
    ASSERT_EQ(frame.depth.height, 60);
    ASSERT_EQ(frame.color.width, 80);
    DepthImage expected;
    reference.renderDepth(trajectory[i], PinholeCamera(smallIntrinsics()), &expected, nullptr,
                          10.0);
    EXPECT_EQ(frame.depth.data, expected.data);
  }
  EXPECT_EQ(frame.timestamp_ns, 133333333);  // 4 / 30 s
  const int64_t last = frame.timestamp_ns;
  EXPECT_FALSE(source.next(&frame));
  EXPECT_EQ(frame.timestamp_ns, last);  // untouched
  source.reset();
  ASSERT_TRUE(source.next(&frame));
  EXPECT_EQ(frame.timestamp_ns, 0);
}

TEST(SyntheticDepthSourceTest, RejectsBadParameters) {
  const std::vector<Transformationd> one{Transformationd()};
  EXPECT_THROW(SyntheticDepthSource(makeSphereScene(), smallIntrinsics(), one, 0.0, 10.0),
               std::invalid_argument);
  EXPECT_THROW(SyntheticDepthSource(makeSphereScene(), smallIntrinsics(), one, 30.0, -1.0),
               std::invalid_argument);
  PinholeIntrinsics bad = smallIntrinsics();
  bad.fx = -1.0;
  EXPECT_THROW(SyntheticDepthSource(makeSphereScene(), bad, one, 30.0, 10.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace cblox
