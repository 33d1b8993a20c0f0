#include "drivers/libcamera/libcamera_source.h"

#include <chrono>
#include <cstdlib>
#include <limits>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "drivers/libcamera/camera_manager_handle.h"
#include "drivers/libcamera/completed_request_queue.h"
#include "test/test_support/contains.h"

namespace cblox {
namespace {

using test::contains;

TEST(LibcameraSourceConfig, DefaultIsValidAndModesParse) {
  EXPECT_EQ(LibcameraSourceConfig{}.validate(), "");
  EXPECT_EQ(parseLibcameraStereoMode("mono"), LibcameraStereoMode::kMono);
  EXPECT_EQ(parseLibcameraStereoMode("side_by_side"), LibcameraStereoMode::kSideBySide);
  EXPECT_EQ(parseLibcameraStereoMode("side-by-side"), LibcameraStereoMode::kSideBySide);
  EXPECT_FALSE(parseLibcameraStereoMode("stereo").has_value());
  EXPECT_EQ(libcameraStereoModeName(LibcameraStereoMode::kSideBySide), "side_by_side");
}

TEST(LibcameraSourceConfig, NamesTheFirstBadField) {
  LibcameraSourceConfig config;
  config.camera.buffer_count = 0;
  EXPECT_TRUE(contains(config.validate(), "camera.buffer_count must be in [1, 32], got 0"));

  config = {};
  config.mode = LibcameraStereoMode::kSideBySide;
  config.camera.pixel_format = "GREY";
  config.camera.width = 1281;
  EXPECT_TRUE(contains(config.validate(), "side_by_side needs an even width"));

  config = {};
  config.stall_timeout_s = 0.0;
  EXPECT_TRUE(contains(config.validate(), "stall_timeout_s must be finite and > 0"));
  config.stall_timeout_s = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(contains(config.validate(), "stall_timeout_s must be finite and > 0"));

  config = {};
  config.restart_backoff_s = -1.0;
  EXPECT_TRUE(contains(config.validate(), "restart_backoff_s must be finite and > 0"));
  config = {};
  config.restart_backoff_max_s = 0.5;
  EXPECT_TRUE(contains(config.validate(), "restart_backoff_max_s must be finite and >= "));
}

TEST(LibcameraSourceConfig, RectifierMustFitTheSideBySideFrame) {
  StereoCameraCalibration raw;
  raw.left.intrinsics = PinholeIntrinsics{400.0, 400.0, 320.0, 240.0, 640, 480};
  raw.right = raw.left;
  raw.T_R_L = Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-0.1, 0, 0));
  raw.source = "rig.yaml";
  std::string error;
  const std::shared_ptr<const StereoRectifier> rectifier = StereoRectifier::create(raw, &error);
  ASSERT_NE(rectifier, nullptr) << error;

  LibcameraSourceConfig config;
  config.rectifier = rectifier;
  EXPECT_TRUE(contains(config.validate(), "a rectifier needs mode side_by_side"));
  config.mode = LibcameraStereoMode::kSideBySide;
  config.camera.width = 1280;
  config.camera.height = 480;
  EXPECT_EQ(config.validate(), "");
  config.camera.width = 640;
  EXPECT_TRUE(contains(config.validate(),
                       "the rectifier's calibration (rig.yaml) is for 640x480 images, but the "
                       "side-by-side frame 640x480 has halves of 320x480"));
}

TEST(LibcameraSource, OpeningAMissingCameraNamesItAndTheCamerasPresent) {
  std::string error;
  const std::shared_ptr<libcamera::CameraManager> manager = sharedCameraManager(&error);
  ASSERT_NE(manager, nullptr) << error;
  LibcameraSourceConfig config;
  config.camera.camera_id = "libcamera:imx219";
  EXPECT_EQ(LibcameraSource::open(config, &error), nullptr);
  EXPECT_TRUE(contains(error, "libcamera camera 'imx219' not found; cameras present: " +
                                  describeLibcameraCameras(*manager)));
  config.stall_timeout_s = -1.0;
  EXPECT_EQ(LibcameraSource::open(config, &error), nullptr);
  EXPECT_TRUE(contains(error, "libcamera source: stall_timeout_s must be"));
}

TEST(LibcameraSource, StreamsFramesFromARealCamera) {
  std::string error;
  const std::shared_ptr<libcamera::CameraManager> manager = sharedCameraManager(&error);
  ASSERT_NE(manager, nullptr) << error;
  if (manager->cameras().empty()) GTEST_SKIP() << "no libcamera camera present";
  LibcameraSourceConfig config;
  config.camera.camera_id = "0";
  std::unique_ptr<LibcameraSource> source = LibcameraSource::open(config, &error);
  if (source == nullptr) GTEST_SKIP() << "camera 0 cannot stream the default config: " << error;
  EXPECT_TRUE(source->info().name.starts_with("libcamera:"));
  CaptureFrame frame;
  int64_t last_id = -1, last_ns = 0;
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame) << error;
    EXPECT_GT(frame.frame_id, last_id);
    EXPECT_GT(frame.timestamp_ns, last_ns);
    EXPECT_EQ(frame.left.width, config.camera.width);
    last_id = frame.frame_id;
    last_ns = frame.timestamp_ns;
  }
  // On the system clock: within a second of now.
  const int64_t now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  EXPECT_LT(std::abs(now_ns - last_ns), 1'000'000'000);
  EXPECT_TRUE(contains(source->health(), "streaming"));
}

TEST(LibcameraDriverParts, CompletedRequestQueueHandsOverInOrderAndCloses) {
  // The queue only passes pointers along; these are never dereferenced.
  alignas(8) char storage[2];
  auto* a = reinterpret_cast<libcamera::Request*>(&storage[0]);
  auto* b = reinterpret_cast<libcamera::Request*>(&storage[1]);
  CompletedRequestQueue queue;
  libcamera::Request* got = nullptr;
  EXPECT_EQ(queue.pop(std::chrono::milliseconds(1), &got),
            CompletedRequestQueue::PopResult::kTimeout);
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    queue.push(a);
    queue.push(b);
  });
  ASSERT_EQ(queue.pop(std::chrono::seconds(5), &got), CompletedRequestQueue::PopResult::kRequest);
  EXPECT_EQ(got, a);
  producer.join();
  EXPECT_EQ(queue.size(), 1u);
  queue.close();
  ASSERT_EQ(queue.pop(std::chrono::seconds(5), &got), CompletedRequestQueue::PopResult::kRequest);
  EXPECT_EQ(got, b);  // queued before close(): still handed out
  EXPECT_EQ(queue.pop(std::chrono::seconds(5), &got), CompletedRequestQueue::PopResult::kClosed);
  queue.clear();
  EXPECT_EQ(queue.pop(std::chrono::milliseconds(1), &got),
            CompletedRequestQueue::PopResult::kTimeout);
}

}  // namespace
}  // namespace cblox
