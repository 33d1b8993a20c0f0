// The online disparity correction: its combination of window estimates, frames built with a
// correction, the measurements bundle adjustment takes, and the whole SLAM system finding a
// right principal point error the simulator puts into its rig.

#include "core/tracking/disparity_correction.h"

#include <cmath>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "core/tracking/feature_measurement.h"
#include "core/tracking/frame_builder.h"
#include "core/tracking/slam_system.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

TEST(DisparityCorrectionTest, TheMedianOfTheWindowOnceItIsSettled) {
  DisparityCorrectionConfig config;
  config.window = 5;
  config.min_estimates = 3;
  config.max_spread_px = 0.3;
  config.settled_tolerance_px = 0.15;
  DisparityCorrection correction(config);
  correction.addEstimate(1.0);
  correction.addEstimate(1.2);
  EXPECT_EQ(correction.correctionPx(), 0.0f);  // two estimates: not yet
  correction.addEstimate(1.1);
  EXPECT_FLOAT_EQ(correction.correctionPx(), 1.1f);
  correction.addEstimate(3.0);  // one outlier does not move the median far
  EXPECT_FLOAT_EQ(correction.correctionPx(), 1.15f);
  EXPECT_FALSE(correction.settled());  // four estimates in a window of five
  EXPECT_EQ(correction.estimateInterval(), config.every_keyframes);
  correction.addEstimate(1.3);
  EXPECT_FLOAT_EQ(correction.correctionPx(), 1.2f);
  EXPECT_TRUE(correction.settled());
  EXPECT_EQ(correction.estimateInterval(), config.settled_every_keyframes);
  correction.addEstimate(9.0);  // beyond max_abs_px: refused
  DisparityCorrectionStats stats = correction.stats();
  EXPECT_EQ(stats.estimates, 5u);
  EXPECT_EQ(stats.refused, 1u);
  EXPECT_EQ(stats.updates, 3u);
  EXPECT_DOUBLE_EQ(stats.last_estimate_px, 1.3);
  // Window {1.2, 1.1, 3.0, 1.3, -2.0}: median 1.2, deviations {0, 0.1, 1.8, 0.1, 3.2}, spread
  // 1.4826 x 0.1 within 0.3: applied. Then {1.1, 3.0, 1.3, -2.0, 4.0}: median 1.3,
  // deviations {0.2, 1.7, 0, 3.3, 2.7}, spread 1.4826 x 1.7: kept at 1.2.
  correction.addEstimate(-2.0);
  EXPECT_FLOAT_EQ(correction.correctionPx(), 1.2f);
  EXPECT_FALSE(correction.settled());  // the last estimate is 3.2 px from the correction
  correction.addEstimate(4.0);
  stats = correction.stats();
  EXPECT_FLOAT_EQ(correction.correctionPx(), 1.2f);
  EXPECT_FALSE(correction.settled());  // the window disagrees: estimate often again
  EXPECT_NEAR(stats.spread_px, 1.4826 * 1.7, 1e-9);
  EXPECT_DOUBLE_EQ(stats.correction_px, 1.2);

  // Medians within min_correction_px of 0 leave the calibration alone.
  config.min_correction_px = 0.1;
  DisparityCorrection small(config);
  for (const double e : {0.08, 0.09, 0.05}) small.addEstimate(e);
  EXPECT_EQ(small.correctionPx(), 0.0f);
  EXPECT_EQ(small.stats().updates, 1u);
  small.addEstimate(0.2);  // window median 0.085
  small.addEstimate(0.3);  // 0.09
  EXPECT_EQ(small.correctionPx(), 0.0f);
  small.addEstimate(0.4);  // {0.09, 0.05, 0.2, 0.3, 0.4}: 0.2
  EXPECT_FLOAT_EQ(small.correctionPx(), 0.2f);
  config.min_correction_px = -1.0;
  EXPECT_THROW(DisparityCorrection bad(config), std::invalid_argument);
  config.min_correction_px = 0.0;

  config.enabled = false;
  DisparityCorrection off(config);
  for (int i = 0; i < 5; ++i) off.addEstimate(1.0);
  EXPECT_EQ(off.correctionPx(), 0.0f);
  EXPECT_EQ(off.stats().estimates, 0u);
}

TEST(DisparityCorrectionTest, RefusesABadConfigNamingTheField) {
  const auto message = [](DisparityCorrectionConfig c) {
    try {
      DisparityCorrection correction(c);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  DisparityCorrectionConfig c;
  c.min_estimates = c.window + 1;
  EXPECT_NE(message(c).find("min_estimates"), std::string::npos);
  c = DisparityCorrectionConfig{};
  c.max_spread_px = 0.0;
  EXPECT_NE(message(c).find("max_spread_px"), std::string::npos);
  c = DisparityCorrectionConfig{};
  c.every_keyframes = 0;
  EXPECT_NE(message(c).find("every_keyframes"), std::string::npos);
  c = DisparityCorrectionConfig{};
  c.solver.iterations = 0;
  EXPECT_NE(message(c).find("solver: iterations"), std::string::npos);
  EXPECT_EQ(message(DisparityCorrectionConfig{}), "");
}

// One exact frame of the simulator's room: (left, right, calibration).
struct RoomFrame {
  CaptureFrame frame;
  RectifiedStereoCalibration calibration;
};

RoomFrame roomFrame() {
  SourceConfig options;
  options.max_frames = 1;
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  EXPECT_NE(source, nullptr) << error;
  RoomFrame room;
  if (!source) return room;
  room.calibration = *source->info().stereo;
  EXPECT_EQ(source->next(&room.frame, &error), FrameSource::Status::kFrame) << error;
  return room;
}

TEST(DisparityCorrectionTest, AFrameBuiltWithACorrectionHasItsDisparitiesGrownByIt) {
  const RoomFrame room = roomFrame();
  const TrackingCamera camera =
      makeTrackingCamera(room.calibration.intrinsics, room.calibration.baseline_m);
  FrameBuilder builder(camera, FrameBuilderConfig{}, nullptr);
  const auto raw = builder.fromStereo(room.frame.left, room.frame.right);
  const auto corrected = builder.fromStereo(room.frame.left, room.frame.right, 0.75f);
  EXPECT_TRUE(raw->stereo_matched);
  EXPECT_EQ(raw->disparity_correction_px, 0.0f);
  EXPECT_EQ(corrected->disparity_correction_px, 0.75f);
  ASSERT_EQ(raw->size(), corrected->size());
  size_t matched = 0;
  for (size_t i = 0; i < raw->size(); ++i) {
    ASSERT_EQ(raw->hasDepth(i), corrected->hasDepth(i)) << i;  // room disparities exceed 0.75
    if (!raw->hasDepth(i)) continue;
    ++matched;
    EXPECT_FLOAT_EQ(corrected->right_u[i], raw->right_u[i] - 0.75f);
    const float disparity = corrected->keypoints[i].u - corrected->right_u[i];
    EXPECT_FLOAT_EQ(corrected->depth[i], static_cast<float>(camera.bf()) / disparity);
  }
  EXPECT_GT(matched, 300u);
}

TEST(DisparityCorrectionTest, BundleAdjustmentTakesTheCorrectionInUse) {
  const ScalePyramid pyramid(8, 1.2);
  FrameFeatures f;
  f.keypoints = {Keypoint{100.0f, 50.0f, 0.0f, 0.0f, 0}, Keypoint{200.0f, 60.0f, 0.0f, 0.0f, 1},
                 Keypoint{300.0f, 70.0f, 0.0f, 0.0f, 0}};
  f.right_u = {90.0f, -1.0f, 299.5f};
  f.depth = {5.0f, -1.0f, 100.0f};
  f.disparity_correction_px = 0.5f;
  f.stereo_matched = true;
  // Matched columns 90.5 and 300.0; corrected by 1.5 they are 89.0 and 298.5.
  EXPECT_DOUBLE_EQ(featureMeasurement(f, 0, pyramid, 1.5f).u_right, 89.0);
  EXPECT_DOUBLE_EQ(featureMeasurement(f, 2, pyramid, 1.5f).u_right, 298.5);
  EXPECT_DOUBLE_EQ(featureMeasurement(f, 0, pyramid, 0.5f).u_right, 90.0);  // as built
  EXPECT_EQ(featureMeasurement(f, 1, pyramid, 1.5f).u_right, -1.0);          // mono stays
  // A correction of -0.5 leaves the third no positive disparity (300.5 > 300): mono.
  EXPECT_EQ(featureMeasurement(f, 2, pyramid, -0.5f).u_right, -1.0);
  EXPECT_DOUBLE_EQ(featureMeasurement(f, 1, pyramid, 1.5f).inv_sigma2, pyramid.invSigma2(1));
  // RGB-D's virtual columns are never corrected.
  f.stereo_matched = false;
  EXPECT_DOUBLE_EQ(featureMeasurement(f, 0, pyramid, 1.5f).u_right, 90.0);
}

TEST(DisparityCorrectionTest, TheSlamSystemFindsTheRigsRightPrincipalPointError) {
  // The room's rig with its right image rendered 1 px off the published principal point:
  // every disparity 1 px small (2-10 % of the room's), the depths too large.
  std::string error;
  const auto vocabulary = BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &error);
  ASSERT_TRUE(vocabulary.has_value()) << error;
  SourceConfig options;
  options.max_frames = 240;
  options.sim.renderer.rig.right_cx_error_px = 1.0;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  ASSERT_NE(source, nullptr) << error;
  const RectifiedStereoCalibration& calibration = *source->info().stereo;
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  SlamSystemConfig config;
  config.loop_closing_enabled = false;
  SlamSystem slam(camera, config, &*vocabulary);
  CaptureFrame frame;
  int tracked = 0;  // frames tracked since the map started
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const TrackingResult r =
        slam.trackStereo(static_cast<uint64_t>(frame.frame_id), frame.timestamp_ns, frame.left,
                         frame.right, frame.T_G_C->inverse());
    // The first frames have a few too few stereo matches to start the map (1 px of error
    // moves some right corners out of the SAD search); once started, none is lost.
    if (r.state == TrackingState::kOk) {
      ++tracked;
    } else {
      EXPECT_EQ(tracked, 0) << "frame " << frame.frame_id << ": " << r.reason;
    }
    slam.waitUntilIdle();  // every keyframe's local BA, whatever this machine's load
  }
  slam.stop();
  const DisparityCorrectionStats stats = slam.disparityCorrectionStats();
  std::printf("disparity correction: %.3f px (%lu estimates, spread %.3f px)\n",
              stats.correction_px, static_cast<unsigned long>(stats.estimates), stats.spread_px);
  EXPECT_GE(tracked, 200);
  EXPECT_GE(stats.updates, 1u);
  EXPECT_NEAR(slam.map().disparityCorrectionPx(), 1.0, 0.2);
}

}  // namespace
}  // namespace cblox
