#include "daemon/common/lcm_messages.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

/// Encodes and decodes through LCM's wire format.
template <typename Msg>
Msg wireRoundTrip(const Msg& msg) {
  std::vector<uint8_t> buffer(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  Msg decoded;
  EXPECT_EQ(decoded.decode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  return decoded;
}

TEST(LcmMessagesTest, ImagesRoundTrip) {
  GrayImage gray(5, 3);
  for (size_t i = 0; i < gray.data.size(); ++i) gray.data[i] = static_cast<uint8_t>(17 * i);
  GrayImage gray_back;
  std::string error;
  ASSERT_TRUE(fromImageMsg(wireRoundTrip(toImageMsg(gray, 42, "left")), &gray_back, &error))
      << error;
  EXPECT_EQ(gray_back.data, gray.data);

  ColorImage color(4, 2);
  color(1, 1) = Color{255, 10, 3};
  ColorImage color_back;
  const image_t color_msg = toImageMsg(color, 42, "rgb");
  EXPECT_EQ(color_msg.pixel_format, image_t::RGB8);
  ASSERT_TRUE(fromImageMsg(wireRoundTrip(color_msg), &color_back, &error)) << error;
  EXPECT_EQ(color_back(1, 1), (Color{255, 10, 3}));
  // Colour to grey with BT.601 weights: (299 * 255 + 587 * 10 + 114 * 3) / 1000 = 82.
  ASSERT_TRUE(fromImageMsg(color_msg, &gray_back, &error));
  EXPECT_EQ(gray_back(1, 1), 82);
}

TEST(LcmMessagesTest, DepthRoundTripsExactlyAsFloatAndToTheMillimetreAsUint16) {
  DepthImage depth(3, 2);
  depth(0, 0) = 1.23456f;
  depth(1, 0) = 0.0f;
  depth(2, 0) = std::nanf("");
  depth(0, 1) = 70.0f;  // beyond 65.535 m: saturates in u16
  DepthImage back;
  std::string error;
  ASSERT_TRUE(fromDepthImageMsg(
      wireRoundTrip(toDepthImageMsg(depth, 1, "d", DepthEncoding::kFloat32Metres)), &back, &error))
      << error;
  EXPECT_EQ(back(0, 0), 1.23456f);
  EXPECT_EQ(back(1, 0), 0.0f);
  EXPECT_EQ(back(2, 0), 0.0f);
  EXPECT_EQ(back(0, 1), 70.0f);
  const image_t u16 = toDepthImageMsg(depth, 1, "d", DepthEncoding::kUint16Millimetres);
  EXPECT_EQ(u16.depth_scale, 0.001);
  ASSERT_TRUE(fromDepthImageMsg(wireRoundTrip(u16), &back, &error)) << error;
  EXPECT_NEAR(back(0, 0), 1.235f, 1e-6f);
  EXPECT_EQ(back(2, 0), 0.0f);
  EXPECT_NEAR(back(0, 1), 65.535f, 1e-4f);
}

TEST(LcmMessagesTest, PosesAndCalibrationRoundTrip) {
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.1, -0.2, 3.0, 0.3, 0.2, -0.1;
  const Transformationd T = Transformationd::exp(xi);
  std::string error;
  const auto back = fromPoseMsg(wireRoundTrip(toPoseMsg(T)), &error);
  ASSERT_TRUE(back.has_value()) << error;
  EXPECT_TRUE(back->isApprox(T, 1e-12));
  pose_t bad = toPoseMsg(T);
  bad.orientation[0] = 2.0;
  EXPECT_FALSE(fromPoseMsg(bad, &error).has_value());
  EXPECT_NE(error.find("norm"), std::string::npos);

  const PinholeIntrinsics K{458.0, 457.0, 367.2, 248.4, 752, 480};
  const auto K_back = fromCalibrationMsg(wireRoundTrip(toCalibrationMsg("cam0", K, T)), &error);
  ASSERT_TRUE(K_back.has_value()) << error;
  EXPECT_EQ(K_back->fx, 458.0);
  EXPECT_EQ(K_back->cy, 248.4);
  EXPECT_EQ(K_back->width, 752);
  camera_calibration_t distorted = toCalibrationMsg("cam0", K, T);
  distorted.distortion_model = "radtan";
  EXPECT_FALSE(fromCalibrationMsg(distorted, &error).has_value());
  EXPECT_NE(error.find("radtan"), std::string::npos);
}

TEST(LcmMessagesTest, RejectsMalformedImages) {
  image_t msg = toImageMsg(GrayImage(4, 4, 7), 0, "cam");
  GrayImage gray;
  DepthImage depth;
  std::string error;
  image_t truncated = msg;
  truncated.data.resize(10);
  EXPECT_FALSE(fromImageMsg(truncated, &gray, &error));
  EXPECT_NE(error.find("expected 16"), std::string::npos) << error;
  image_t bad_format = msg;
  bad_format.pixel_format = 42;
  EXPECT_FALSE(fromImageMsg(bad_format, &gray, &error));
  EXPECT_NE(error.find("unknown pixel_format 42"), std::string::npos) << error;
  image_t bad_stride = msg;
  bad_stride.row_stride = 2;
  EXPECT_FALSE(fromImageMsg(bad_stride, &gray, &error));
  EXPECT_FALSE(fromDepthImageMsg(msg, &depth, &error));  // grey is not depth
  EXPECT_NE(error.find("not DEPTH_U16"), std::string::npos) << error;
  image_t zero_scale =
      toDepthImageMsg(DepthImage(2, 2, 1.0f), 0, "d", DepthEncoding::kUint16Millimetres);
  zero_scale.depth_scale = 0.0;
  EXPECT_FALSE(fromDepthImageMsg(zero_scale, &depth, &error));
}

TEST(LcmMessagesTest, FrameMessagesCarryCalibrationIdsAndPoses) {
  SourceInfo info;
  info.stereo = RectifiedStereoCalibration{PinholeIntrinsics{400, 400, 79.5, 59.5, 160, 120}, 0.11,
                                           Transformationd::Identity()};
  info.depth_intrinsics = PinholeIntrinsics{400, 400, 79.5, 59.5, 160, 120};
  info.depth_max_m = 8.0;
  CaptureFrame frame;
  frame.frame_id = 7;
  frame.left = GrayImage(160, 120, 1);
  frame.right = GrayImage(160, 120, 2);
  frame.depth = DepthImage(160, 120, 2.0f);
  frame.T_G_C = Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 2, 3));
  const stereo_pair_t stereo = wireRoundTrip(toStereoPairMsg(frame, info, 1000));
  EXPECT_EQ(stereo.frame_id, 7);
  EXPECT_EQ(stereo.utime, 1000);
  EXPECT_TRUE(stereo.rectified);
  EXPECT_DOUBLE_EQ(stereo.T_L_R.position[0], 0.11);
  EXPECT_DOUBLE_EQ(stereo.right_calibration.T_B_C.position[0], 0.11);
  EXPECT_EQ(stereo.right.data[0], 2);
  const depth_frame_t depth =
      wireRoundTrip(toDepthFrameMsg(frame, info, 1000, DepthEncoding::kFloat32Metres));
  EXPECT_FALSE(depth.has_color);
  EXPECT_EQ(depth.color.width, 0);
  EXPECT_EQ(depth.max_depth_m, 8.0f);
  const pose_stamped_t gt = wireRoundTrip(toGroundTruthMsg(frame, 1000));
  EXPECT_EQ(gt.frame, "G");
  EXPECT_EQ(gt.frame_id, 7);
  EXPECT_EQ(gt.T_G_C.position[2], 3.0);
}

TEST(LcmMessagesTest, StereoCalibrationOfARectifiedPairAndWhatIsWrongWithOthers) {
  SourceInfo info;
  const Transformationd T_B_L(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.1, 0.0));
  info.stereo =
      RectifiedStereoCalibration{PinholeIntrinsics{400, 401, 79.5, 59.5, 160, 120}, 0.12, T_B_L};
  CaptureFrame frame;
  frame.left = GrayImage(160, 120, 1);
  frame.right = GrayImage(160, 120, 2);
  const stereo_pair_t msg = wireRoundTrip(toStereoPairMsg(frame, info, 1000));
  std::string error;
  const auto calibration = fromStereoCalibrationMsg(msg, &error);
  ASSERT_TRUE(calibration.has_value()) << error;
  EXPECT_EQ(calibration->intrinsics.fy, 401.0);
  EXPECT_EQ(calibration->intrinsics.height, 120);
  EXPECT_EQ(calibration->baseline_m, 0.12);
  EXPECT_TRUE(calibration->T_B_L.isApprox(T_B_L, 0.0));

  struct Case {
    void (*spoil)(stereo_pair_t*);
    const char* message;
  };
  const Case cases[] = {
      {[](stereo_pair_t* m) { m->rectified = false; }, "not rectified"},
      {[](stereo_pair_t* m) { m->right_calibration.distortion_model = "radtan"; }, "radtan"},
      {[](stereo_pair_t* m) { m->right_calibration.cx += 0.5; }, "calibrations differ"},
      {[](stereo_pair_t* m) { m->left_calibration.fx = -1.0; }, "calibration left"},
      {[](stereo_pair_t* m) { m->T_L_R.position[0] = -0.12; }, "T_L_R must be a translation"},
      {[](stereo_pair_t* m) { m->T_L_R.position[2] = 0.01; }, "T_L_R must be a translation"},
      {[](stereo_pair_t* m) {
         m->T_L_R.orientation[0] = std::cos(0.005);
         m->T_L_R.orientation[2] = std::sin(0.005);
       },
       "T_L_R must be a translation"},
      {[](stereo_pair_t* m) { m->T_L_R.orientation[0] = 3.0; }, "T_L_R: pose quaternion norm"},
      {[](stereo_pair_t* m) { m->left_calibration.T_B_C.position[0] = std::nan(""); },
       "left_calibration.T_B_C"},
  };
  for (const Case& c : cases) {
    stereo_pair_t bad = msg;
    c.spoil(&bad);
    error.clear();
    EXPECT_FALSE(fromStereoCalibrationMsg(bad, &error).has_value()) << c.message;
    EXPECT_NE(error.find(c.message), std::string::npos) << error;
  }
}

TEST(LcmMessagesTest, TrackerMessagesRoundTrip) {
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.5, -1.0, 2.0, 0.1, -0.2, 0.3;
  const Transformationd T = Transformationd::exp(xi);
  std::string error;

  const frame_pose_t pose =
      wireRoundTrip(toFramePoseMsg(1234, 56, T, frame_pose_t::RELOCALIZED, true, 2, 77));
  EXPECT_EQ(pose.utime, 1234);
  EXPECT_EQ(pose.frame_id, 56);
  EXPECT_EQ(pose.tracking_state, frame_pose_t::RELOCALIZED);
  EXPECT_TRUE(pose.tracking_jump);
  EXPECT_EQ(pose.map_epoch, 2);
  EXPECT_EQ(pose.reference_keyframe_id, 77);
  EXPECT_TRUE(fromPoseMsg(pose.T_G_C, &error)->isApprox(T, 1e-12));
  const frame_pose_t lost =
      wireRoundTrip(toFramePoseMsg(1, 2, std::nullopt, frame_pose_t::LOST, false, 0));
  EXPECT_EQ(lost.reference_keyframe_id, -1);  // the default: none
  EXPECT_EQ(toFramePoseMsg(1, 2, T, frame_pose_t::OK, false, 0, -5).reference_keyframe_id, -1);
  EXPECT_TRUE(fromPoseMsg(lost.T_G_C, &error)->isApprox(Transformationd::Identity(), 0.0));

  const keyframe_t keyframe = wireRoundTrip(toKeyframeMsg(99, 3, 56, T, {4, 8, 15, 16, 23, 42}, 5));
  EXPECT_EQ(keyframe.utime, 99);
  EXPECT_EQ(keyframe.map_epoch, 5);
  EXPECT_EQ(keyframe.keyframe_id, 3);
  EXPECT_EQ(keyframe.frame_id, 56);
  EXPECT_EQ(keyframe.num_landmarks, 6);
  EXPECT_EQ(keyframe.landmark_ids, (std::vector<int64_t>{4, 8, 15, 16, 23, 42}));
  EXPECT_TRUE(fromPoseMsg(keyframe.T_G_K, &error)->isApprox(T, 1e-12));

  const keyframe_pose_batch_t batch = wireRoundTrip(toKeyframePoseBatchMsg(
      77, keyframe_pose_batch_t::GLOBAL_BA, {{0, Transformationd::Identity()}, {3, T}}, 6));
  EXPECT_EQ(batch.utime, 77);
  EXPECT_EQ(batch.map_epoch, 6);
  EXPECT_EQ(batch.reason, keyframe_pose_batch_t::GLOBAL_BA);
  EXPECT_EQ(batch.num_keyframes, 2);
  EXPECT_EQ(batch.keyframe_ids, (std::vector<int64_t>{0, 3}));
  EXPECT_TRUE(fromPoseMsg(batch.poses[1], &error)->isApprox(T, 1e-12));
  EXPECT_EQ(
      wireRoundTrip(toKeyframePoseBatchMsg(1, keyframe_pose_batch_t::LOCAL_BA, {}, 0)).num_keyframes,
      0);
}

}  // namespace
}  // namespace cblox
