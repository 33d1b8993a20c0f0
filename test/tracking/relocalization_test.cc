// Relocalization: after tracking part of the room, the camera sees nothing (black frames:
// LOST, with a reason), then reappears at a place mapped earlier: the tracker must find
// it again through the keyframe database and PnP RANSAC, at the true pose.

#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/tracking/slam_system.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

TEST(RelocalizationTest, LostOnBlackFramesThenRelocalizedAtAnEarlierPlace) {
  std::string error;
  const auto vocabulary = BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &error);
  ASSERT_TRUE(vocabulary.has_value()) << error;
  SourceConfig options;
  options.trajectory = "loop";
  options.max_frames = 160;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  ASSERT_NE(source, nullptr) << error;
  const RectifiedStereoCalibration& calibration = *source->info().stereo;
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  SlamSystemConfig config;
  config.loop_closing_enabled = false;
  SlamSystem slam(camera, config, &*vocabulary);
  std::vector<CaptureFrame> frames;
  CaptureFrame frame;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) frames.push_back(frame);
  ASSERT_EQ(frames.size(), 160u);
  uint64_t id = 0;
  int64_t t = 0;
  for (const CaptureFrame& f : frames) {
    const TrackingResult r =
        slam.trackStereo(id++, t += 50'000'000, f.left, f.right, frames[0].T_G_C->inverse());
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << f.frame_id << ": " << r.reason;
    slam.waitUntilIdle();  // every keyframe reaches the database
  }
  ASSERT_GT(slam.databaseSize(), 2u);
  // Darkness: no features, tracking is lost and says why.
  const GrayImage black(frames[0].left.width, frames[0].left.height, 0);
  for (int i = 0; i < 3; ++i) {
    const TrackingResult r = slam.trackStereo(id++, t += 50'000'000, black, black);
    EXPECT_EQ(r.state, TrackingState::kLost);
    EXPECT_FALSE(r.reason.empty());
  }
  // The camera reappears where it was at frame 40 (half a room away from frame 159).
  const CaptureFrame& back = frames[40];
  ASSERT_GT((back.T_G_C->translation() - frames[159].T_G_C->translation()).norm(), 0.5);
  const TrackingResult r = slam.trackStereo(id++, t += 50'000'000, back.left, back.right);
  ASSERT_EQ(r.state, TrackingState::kOk) << r.reason;
  EXPECT_TRUE(r.relocalized);
  const double error_m = (r.T_C_G->inverse().translation() - back.T_G_C->translation()).norm();
  std::printf("relocalized at frame 40's place: error %.4f m, %d inliers\n", error_m, r.inliers);
  EXPECT_LT(error_m, 0.05);
  // Tracking goes on from there.
  const TrackingResult next =
      slam.trackStereo(id++, t += 50'000'000, frames[41].left, frames[41].right);
  EXPECT_EQ(next.state, TrackingState::kOk) << next.reason;
  EXPECT_FALSE(next.relocalized);
  slam.stop();
}

}  // namespace
}  // namespace cblox
