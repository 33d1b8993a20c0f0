// RGB-D tracking (ORB-SLAM2's RGB-D mode: depth from the depth image, a virtual right
// coordinate) on the 50 real 7-Scenes frames in ../shared/data, against their poses.

#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "core/eval/trajectory_metrics.h"
#include "core/tracking/slam_system.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

GrayImage toGray(const ColorImage& color) {
  GrayImage gray(color.width, color.height);
  for (size_t i = 0; i < color.data.size(); ++i) {
    const Color& c = color.data[i];
    gray.data[i] = static_cast<uint8_t>((299 * c.r + 587 * c.g + 114 * c.b + 500) / 1000);
  }
  return gray;
}

TEST(RgbdTrackingTest, SevenScenesFramesTrackWithinThreeCentimetres) {
  const std::string folder = std::string(CBLOX_SHARED_DATA_DIR) + "/7scenes-rgbd-50";
  if (!std::filesystem::is_directory(folder)) GTEST_SKIP() << folder << " is absent";
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource("7scenes:" + folder, {}, &error);
  ASSERT_NE(source, nullptr) << error;
  // ORB-SLAM2's TUM RGB-D settings: bf = 40 (a virtual 7 cm baseline at fx = 585),
  // close points up to 40 baselines.
  const PinholeIntrinsics& intrinsics = *source->info().depth_intrinsics;
  const TrackingCamera camera = makeTrackingCamera(intrinsics, 40.0 / intrinsics.fx);
  SlamSystemConfig config;
  SlamSystem slam(camera, config, nullptr);
  StampedTrajectory truth, estimate;
  CaptureFrame frame;
  int lost = 0;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    ASSERT_TRUE(frame.T_G_C.has_value());
    const TrackingResult r = slam.trackRgbd(static_cast<uint64_t>(frame.frame_id),
                                            frame.timestamp_ns, toGray(frame.color), frame.depth);
    const double t = static_cast<double>(frame.timestamp_ns) * 1e-9;
    truth.push_back({t, *frame.T_G_C});
    if (r.state != TrackingState::kOk) {
      ++lost;
      continue;
    }
    estimate.push_back({t, r.T_C_G->inverse()});
  }
  slam.waitUntilIdle();
  slam.stop();
  EXPECT_EQ(lost, 0);
  ASSERT_GE(estimate.size(), 45u);
  AssociationConfig association;
  const auto pairs = associateTrajectories(truth, estimate, association);
  ASSERT_EQ(pairs.size(), estimate.size());
  const auto ate = computeAte(pairs, AlignmentType::kSE3, &error);
  ASSERT_TRUE(ate.has_value()) << error;
  std::printf("7-Scenes RGB-D: %zu frames tracked, ATE RMSE %.4f m (max %.4f m), %zu keyframes\n",
              estimate.size(), ate->translation_m.rmse, ate->translation_m.max,
              slam.map().numKeyframes());
  EXPECT_LT(ate->translation_m.rmse, 0.03);
}

}  // namespace
}  // namespace cblox
