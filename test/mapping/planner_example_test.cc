// The README's planner example ("The map for a planner"), extracted from README.md at
// configure time into planner_example.inc, compiled here and run on the simulated room.

#include <chrono>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/mapping/mapper.h"
#include "test/mapping/room_frames.h"
#include "test/test_support/temp_dir.h"

#include "planner_example.inc"

namespace cblox {
namespace {

TEST(PlannerExampleTest, TheReadmeExampleRunsOnTheSimulatedRoom) {
  test::TempDir dir("planner_example");
  MapperConfig config;
  config.layer = LayerConfig{0.04f, 8};
  config.output_dir = dir.path().string();
  // The ray-casting integrator carves the free space between camera and surface; the
  // projective one (the default) observes only the band around surfaces.
  config.integrator_type = IntegratorType::kFast;
  // Every frame whole: under ThreadSanitizer the default 80 ms budget cuts most rays.
  config.integrator.max_integration_time_s = 0.0;
  config.planning.enabled = true;
  Mapper mapper(config);
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const std::vector<SyntheticFrame>& frames = roomFrames();
  for (size_t i = 0; i < frames.size(); ++i) {
    ASSERT_TRUE(mapper.onDepthFrame(depthFrame(frames[i], static_cast<int64_t>(i))));
    ASSERT_TRUE(mapper.onFramePose(groundTruthPose(utimeOf(frames[i]), frames[i].T_G_C)));
    ASSERT_TRUE(mapper.waitUntilIdle(std::chrono::seconds(60)));  // a hang guard
  }
  ASSERT_TRUE(mapper.syncPlanningMap(std::chrono::milliseconds(60000)));
  testing::internal::CaptureStdout();
  ::printClearanceAlongX(mapper);
  const std::string out = testing::internal::GetCapturedStdout();
  std::istringstream lines(out);
  std::string line;
  int count = 0, free = 0;
  while (std::getline(lines, line)) {
    ++count;
    if (line.find(": free, ") != std::string::npos) ++free;
  }
  EXPECT_EQ(count, 9) << out;  // x = -2.0, -1.5, ..., 2.0
  // The orbit at 1.5 m around the room's centre looks at the walls from inside: the line at
  // 1 m height through the middle of the room is observed free space.
  EXPECT_GE(free, 5) << out;
  mapper.stop();
}

}  // namespace
}  // namespace cblox
