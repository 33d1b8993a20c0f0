#include "drivers/v4l2/v4l2_source.h"

#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/calibration/stereo_rectifier.h"
#include "drivers/camera/drop_counter.h"
#include "drivers/camera/reopen_schedule.h"
#include "drivers/v4l2/v4l2_frame_decoder.h"
#include "drivers/v4l2/v4l2_source_config.h"

namespace cblox {
namespace {

constexpr int64_t kS = 1'000'000'000;

// ---- Back-off

TEST(ReopenScheduleTest, DelayDoublesUpToTheCap) {
  EXPECT_EQ(reopenDelaySeconds(1, 1.0, 30.0), 1.0);
  EXPECT_EQ(reopenDelaySeconds(2, 1.0, 30.0), 2.0);
  EXPECT_EQ(reopenDelaySeconds(3, 1.0, 30.0), 4.0);
  EXPECT_EQ(reopenDelaySeconds(5, 1.0, 30.0), 16.0);
  EXPECT_EQ(reopenDelaySeconds(6, 1.0, 30.0), 30.0);
  EXPECT_EQ(reopenDelaySeconds(1000, 1.0, 30.0), 30.0);
  EXPECT_EQ(reopenDelaySeconds(0, 0.5, 30.0), 0.5);
  EXPECT_EQ(reopenDelaySeconds(3, 0.25, 0.75), 0.75);
}

TEST(ReopenScheduleTest, FormatsSeconds) {
  EXPECT_EQ(formatSeconds(4.0), "4");
  EXPECT_EQ(formatSeconds(0.5), "0.5");
  EXPECT_EQ(formatSeconds(3.21), "3.3");  // rounded up
  EXPECT_EQ(formatSeconds(0.0), "0");
  EXPECT_EQ(formatSeconds(-1.0), "0");
}

TEST(ReopenScheduleTest, AttemptsFollowTheBackOff) {
  ReopenSchedule schedule(1.0, 4.0);
  EXPECT_FALSE(schedule.reopening());
  EXPECT_EQ(schedule.status("/dev/video0", 0), "");
  schedule.lost(100 * kS);
  EXPECT_TRUE(schedule.reopening());
  EXPECT_EQ(schedule.attempt(), 1);
  EXPECT_EQ(schedule.nextAttemptNs(), 101 * kS);
  EXPECT_FALSE(schedule.due(101 * kS - 1));
  EXPECT_TRUE(schedule.due(101 * kS));
  EXPECT_EQ(schedule.status("/dev/video0", 100 * kS),
            "reopening /dev/video0 (attempt 1, next in 1 s)");
  schedule.lost(100 * kS + 1);  // already reopening: unchanged
  EXPECT_EQ(schedule.nextAttemptNs(), 101 * kS);

  schedule.failed(101 * kS);  // attempt 1 failed -> attempt 2 in 2 s
  EXPECT_EQ(schedule.attempt(), 2);
  EXPECT_EQ(schedule.nextAttemptNs(), 103 * kS);
  schedule.failed(103 * kS);  // -> attempt 3 in 4 s
  EXPECT_EQ(schedule.nextAttemptNs(), 107 * kS);
  EXPECT_EQ(schedule.status("/dev/video0", 103 * kS),
            "reopening /dev/video0 (attempt 3, next in 4 s)");
  EXPECT_EQ(schedule.status("/dev/video0", 106 * kS + kS / 2),
            "reopening /dev/video0 (attempt 3, next in 0.5 s)");
  EXPECT_EQ(schedule.status("/dev/video0", 200 * kS),
            "reopening /dev/video0 (attempt 3, next in 0 s)");
  schedule.failed(107 * kS);  // capped at 4 s
  EXPECT_EQ(schedule.nextAttemptNs(), 111 * kS);
  schedule.succeeded();
  EXPECT_FALSE(schedule.reopening());
  EXPECT_EQ(schedule.attempt(), 0);
  EXPECT_EQ(schedule.totalAttempts(), 4);

  schedule.lost(500 * kS);  // a new loss starts over at the minimum
  EXPECT_EQ(schedule.attempt(), 1);
  EXPECT_EQ(schedule.nextAttemptNs(), 501 * kS);
  EXPECT_THROW(ReopenSchedule(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ReopenSchedule(2.0, 1.0), std::invalid_argument);
}

// ---- Drop counting

TEST(DropCounterTest, CountsByKindAndReportsTheFirstOfEach) {
  std::vector<std::string> lines;
  DropCounter drops("v4l2:/dev/video0", [&](const std::string& line) { lines.push_back(line); });
  EXPECT_EQ(drops.summary(), "none");
  drops.count("corrupt", "frame 7 flagged");
  drops.count("corrupt", "frame 9 flagged");
  drops.count("stall", "no frame for 2 s");
  drops.count("corrupt", "frame 12 flagged");
  EXPECT_EQ(drops.count("corrupt"), 3);
  EXPECT_EQ(drops.count("stall"), 1);
  EXPECT_EQ(drops.count("short_buffer"), 0);
  EXPECT_EQ(drops.total(), 4);
  EXPECT_EQ(drops.summary(), "corrupt=3 stall=1");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0],
            "v4l2:/dev/video0: dropped a frame (corrupt): frame 7 flagged (further drops of "
            "this kind are only counted)");
  EXPECT_EQ(lines[1].rfind("v4l2:/dev/video0: dropped a frame (stall): no frame for 2 s", 0), 0u);
  DropCounter silent("x", nullptr);
  silent.count("corrupt", "not reported");
  EXPECT_EQ(silent.count("corrupt"), 1);
}

// ---- Frame decoding by mode (real buffers)

TEST(V4l2FrameDecoderTest, DecodesEachMode) {
  // A 4x2 YUYV frame: Y = 10..17, neutral chroma.
  const std::vector<uint8_t> yuyv = {10, 128, 11, 128, 12, 128, 13, 128,
                                     14, 128, 15, 128, 16, 128, 17, 128};
  const RawImage raw{PixelFormat::kYuyv, 4, 2, 0, yuyv.data(), yuyv.size()};
  V4l2Images images;
  ASSERT_TRUE(decodeV4l2Frame(V4l2Mode::kMono, raw, false, 0.0, &images));
  EXPECT_EQ(images.left.data, (std::vector<uint8_t>{10, 11, 12, 13, 14, 15, 16, 17}));
  EXPECT_TRUE(images.color.empty());
  ASSERT_TRUE(decodeV4l2Frame(V4l2Mode::kMono, raw, true, 0.0, &images));
  EXPECT_EQ(images.color.width, 4);
  EXPECT_EQ(images.color(0, 0), (Color{0, 0, 0}));  // Y 10 is below black

  ASSERT_TRUE(decodeV4l2Frame(V4l2Mode::kSideBySide, raw, false, 0.0, &images));
  EXPECT_EQ(images.left.data, (std::vector<uint8_t>{10, 11, 14, 15}));
  EXPECT_EQ(images.right.data, (std::vector<uint8_t>{12, 13, 16, 17}));

  ASSERT_TRUE(decodeV4l2Frame(V4l2Mode::kStereoPair, raw, false, 0.0, &images));
  EXPECT_EQ(images.left.width, 4);
  EXPECT_TRUE(images.right.empty());

  const std::vector<uint8_t> z16 = {0xD2, 0x04, 0x00, 0x00};  // 1234, 0
  V4l2Images depth;
  ASSERT_TRUE(decodeV4l2Frame(V4l2Mode::kDepth,
                              RawImage{PixelFormat::kZ16, 2, 1, 0, z16.data(), z16.size()}, false,
                              0.001, &depth));
  EXPECT_EQ(depth.depth(0, 0), 1.234f);
  EXPECT_EQ(depth.depth(1, 0), 0.0f);

  // A frame cut short, as a USB transfer error leaves it.
  const ConvertResult short_frame = decodeV4l2Frame(
      V4l2Mode::kMono, RawImage{PixelFormat::kYuyv, 4, 2, 0, yuyv.data(), 10}, false, 0.0, &images);
  EXPECT_EQ(short_frame.error, ConvertError::kShortBuffer);
  EXPECT_EQ(convertErrorName(short_frame.error), "short_buffer");
}

TEST(V4l2FrameDecoderTest, Y8iSideBySideGivesFullWidthViews) {
  // A 5x3 Y8I frame (odd width: no halves) with 4 bytes of padding after each 10-byte row:
  // left (first byte) = 10 v + u, right (second byte) = 100 + 10 v + u.
  const int w = 5, h = 3;
  const size_t stride = 14;
  std::vector<uint8_t> y8i(stride * h, 0xEE);
  std::vector<uint8_t> left_expected, right_expected;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const auto l = static_cast<uint8_t>(10 * v + u);
      const auto r = static_cast<uint8_t>(100 + 10 * v + u);
      y8i[static_cast<size_t>(v) * stride + 2 * static_cast<size_t>(u)] = l;
      y8i[static_cast<size_t>(v) * stride + 2 * static_cast<size_t>(u) + 1] = r;
      left_expected.push_back(l);
      right_expected.push_back(r);
    }
  }
  const RawImage raw{PixelFormat::kY8i, w, h, stride, y8i.data(), y8i.size()};
  V4l2Images images;
  const ConvertResult result = decodeV4l2Frame(V4l2Mode::kSideBySide, raw, false, 0.0, &images);
  ASSERT_TRUE(result) << result.message;
  EXPECT_EQ(images.left.width, w);
  EXPECT_EQ(images.left.height, h);
  EXPECT_EQ(images.right.width, w);
  EXPECT_EQ(images.right.height, h);
  EXPECT_EQ(images.left.data, left_expected);
  EXPECT_EQ(images.right.data, right_expected);
  EXPECT_TRUE(images.depth.empty());
  EXPECT_TRUE(images.color.empty());

  // Any other mode cannot make one image of it, and says which mode can.
  for (V4l2Mode mode : {V4l2Mode::kMono, V4l2Mode::kStereoPair}) {
    const ConvertResult refused = decodeV4l2Frame(mode, raw, true, 0.0, &images);
    EXPECT_EQ(refused.error, ConvertError::kUnsupported) << v4l2ModeName(mode);
    EXPECT_NE(refused.message.find("use mode side_by_side"), std::string::npos) << refused.message;
  }
  EXPECT_EQ(decodeV4l2Frame(V4l2Mode::kDepth, raw, false, 0.001, &images).error,
            ConvertError::kUnsupported);

  // A frame cut short.
  const ConvertResult short_frame = decodeV4l2Frame(
      V4l2Mode::kSideBySide, RawImage{PixelFormat::kY8i, w, h, stride, y8i.data(), 37}, false, 0.0,
      &images);
  EXPECT_EQ(short_frame.error, ConvertError::kShortBuffer);
  EXPECT_TRUE(images.left.empty());
}

// ---- Configuration

TEST(V4l2SourceConfigTest, ModesByName) {
  for (V4l2Mode mode :
       {V4l2Mode::kMono, V4l2Mode::kDepth, V4l2Mode::kStereoPair, V4l2Mode::kSideBySide}) {
    EXPECT_EQ(v4l2ModeFromName(v4l2ModeName(mode)), mode);
  }
  EXPECT_EQ(v4l2ModeFromName("stereo"), std::nullopt);
}

TEST(V4l2SourceConfigTest, ValidationNamesTheField) {
  V4l2SourceConfig config;
  EXPECT_EQ(config.validate(), "");
  config.mode = V4l2Mode::kStereoPair;
  EXPECT_EQ(config.validate(), "devices: mode stereo_pair takes 2 device(s), got 1");
  config.devices = {"/dev/video0", "/dev/video0"};
  EXPECT_EQ(config.validate(), "devices: left and right are the same device /dev/video0");
  config.devices = {"/dev/video0", "/dev/video2"};
  EXPECT_EQ(config.validate(), "");
  config.pair_tolerance_ms = 0.0;
  EXPECT_EQ(config.validate().rfind("pair_tolerance_ms", 0), 0u);

  config = V4l2SourceConfig{};
  config.pixel_format = "H264";
  EXPECT_EQ(config.validate(), "pixel_format: unknown format 'H264'");
  config.pixel_format = "Z16";
  EXPECT_EQ(config.validate(), "pixel_format: Z16 is depth; use mode depth");
  config.mode = V4l2Mode::kDepth;
  EXPECT_EQ(config.validate(), "");
  config.depth_scale_m = 0.0;
  EXPECT_EQ(config.validate().rfind("depth_scale_m", 0), 0u);
  config.depth_scale_m = 0.001;
  config.depth_intrinsics = PinholeIntrinsics{380.0, 380.0, 319.5, 239.5, 848, 480};
  EXPECT_EQ(config.validate(), "depth_intrinsics: size 848x480 differs from the frame 640x480");
  config.pixel_format = "YUYV";
  EXPECT_EQ(config.validate(), "pixel_format: depth mode needs Z16 (or Y16), got YUYV");

  config = V4l2SourceConfig{};
  config.mode = V4l2Mode::kSideBySide;
  config.width = 1281;
  EXPECT_EQ(config.validate(), "width: side_by_side needs an even width, got 1281");
  config = V4l2SourceConfig{};
  config.buffer_count = 1;
  EXPECT_EQ(config.validate(), "buffer_count: must be 2..32, got 1");
  config = V4l2SourceConfig{};
  config.reopen_min_s = 10.0;
  config.reopen_max_s = 5.0;
  EXPECT_EQ(config.validate(), "reopen_min_s/reopen_max_s: need 0 < min <= max");
  config = V4l2SourceConfig{};
  config.stalls_before_reopen = 0;
  EXPECT_EQ(config.validate(), "stalls_before_reopen: must be >= 1");
}

TEST(V4l2SourceConfigTest, Y8iIsOnlyForSideBySide) {
  const std::string refused =
      "pixel_format: Y8I is interleaved stereo (left and right in one frame); use mode "
      "side_by_side";
  V4l2SourceConfig config;
  config.pixel_format = "Y8I";
  config.width = 848;
  config.height = 480;
  EXPECT_EQ(config.validate(), refused);  // mono
  config.mode = V4l2Mode::kDepth;
  EXPECT_EQ(config.validate(), refused);
  config.mode = V4l2Mode::kStereoPair;
  config.devices = {"/dev/video0", "/dev/video2"};
  EXPECT_EQ(config.validate(), refused);

  config = V4l2SourceConfig{};
  config.mode = V4l2Mode::kSideBySide;
  config.pixel_format = "Y8I";
  config.width = 848;
  config.height = 480;
  EXPECT_EQ(config.validate(), "");
  EXPECT_EQ(config.cameraWidth(), 848);  // each view is the full width
  config.pixel_format = "Y8I ";          // the fourcc spelling
  EXPECT_EQ(config.validate(), "");
  // No halves: an odd width is fine for Y8I (and only for it).
  config.width = 1281;
  EXPECT_EQ(config.validate(), "");
  EXPECT_EQ(config.cameraWidth(), 1281);
  config.pixel_format = "GREY";
  EXPECT_EQ(config.validate(), "width: side_by_side needs an even width, got 1281");
  config.width = 2560;
  EXPECT_EQ(config.cameraWidth(), 1280);  // side by side: halves

  config = V4l2SourceConfig{};
  EXPECT_EQ(config.cameraWidth(), 640);  // mono: the frame
}

// ---- Opening (no camera needed for the failures)

TEST(V4l2SourceTest, OpenFailsWithTheDevicesMessage) {
  V4l2SourceConfig config;
  config.devices = {"/dev/video99"};
  std::string error;
  EXPECT_EQ(V4l2Source::open(config, nullptr, &error), nullptr);
  EXPECT_EQ(error, "/dev/video99: no such device");

  config.devices = {"/dev/null"};
  EXPECT_EQ(V4l2Source::open(config, nullptr, &error), nullptr);
  EXPECT_NE(error.find("/dev/null: not a V4L2 device"), std::string::npos) << error;

  config.buffer_count = 0;
  EXPECT_EQ(V4l2Source::open(config, nullptr, &error), nullptr);
  EXPECT_EQ(error, "v4l2 source: buffer_count: must be 2..32, got 0");
}

TEST(V4l2SourceTest, RectifierMustMatchTheCameraSize) {
  StereoCameraCalibration calibration;
  calibration.left.intrinsics = PinholeIntrinsics{300.0, 300.0, 159.5, 119.5, 320, 240};
  calibration.right = calibration.left;
  calibration.T_R_L = Transformationd(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.1, 0, 0));
  calibration.source = "rig.yaml";
  std::string error;
  std::shared_ptr<const StereoRectifier> rectifier = StereoRectifier::create(calibration, &error);
  ASSERT_NE(rectifier, nullptr) << error;

  V4l2SourceConfig config;
  config.mode = V4l2Mode::kSideBySide;
  config.devices = {"/dev/video99"};
  config.width = 1280;
  config.height = 480;
  EXPECT_EQ(V4l2Source::open(config, rectifier, &error), nullptr);
  EXPECT_EQ(error,
            "v4l2 source: the stereo calibration rig.yaml is for 320x240 images, the cameras "
            "deliver 640x480");
  // The right size gets as far as opening the device.
  config.width = 640;
  config.height = 240;
  EXPECT_EQ(V4l2Source::open(config, rectifier, &error), nullptr);
  EXPECT_EQ(error, "/dev/video99: no such device");

  // Y8I interleaves full-width views: the calibration's width is the frame's, not half.
  config.pixel_format = "Y8I";
  EXPECT_EQ(V4l2Source::open(config, rectifier, &error), nullptr);
  EXPECT_EQ(error,
            "v4l2 source: the stereo calibration rig.yaml is for 320x240 images, the cameras "
            "deliver 640x240");
  config.width = 320;
  EXPECT_EQ(V4l2Source::open(config, rectifier, &error), nullptr);
  EXPECT_EQ(error, "/dev/video99: no such device");
}

}  // namespace
}  // namespace cblox
