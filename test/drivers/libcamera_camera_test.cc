#include "drivers/libcamera/libcamera_camera.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/libcamera/camera_manager_handle.h"
#include "drivers/pixel/pixel_convert.h"
#include "test/test_support/contains.h"

namespace cblox {
namespace {

using test::contains;

// The real CameraManager of this machine; no camera is ever faked.
std::shared_ptr<libcamera::CameraManager> manager() {
  std::string error;
  std::shared_ptr<libcamera::CameraManager> m = sharedCameraManager(&error);
  EXPECT_NE(m, nullptr) << error;
  return m;
}

TEST(LibcameraCameraManager, StartsAndIsSharedWhileHeld) {
  const std::shared_ptr<libcamera::CameraManager> first = manager();
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(manager(), first);  // one per process: libcamera aborts on a second
  const std::vector<std::string> ids = libcameraCameraIds(*first);
  const std::string listed = describeLibcameraCameras(*first);
  if (ids.empty()) {
    EXPECT_EQ(listed, "none");
  } else {
    EXPECT_TRUE(contains(listed, "0: " + ids[0]));
  }
  std::printf("  libcamera %s, cameras present: %s\n", libcamera::CameraManager::version().c_str(),
              listed.c_str());
}

TEST(LibcameraCameraManager, RestartsAfterTheLastHolderLetsGo) {
  for (int round = 0; round < 2; ++round) {
    // Each round's manager is stopped and destroyed with its last holder; the next round
    // constructs a new one (libcamera would abort if two existed at once).
    const std::shared_ptr<libcamera::CameraManager> m = manager();
    ASSERT_NE(m, nullptr);
    EXPECT_FALSE(describeLibcameraCameras(*m).empty());
  }
}

TEST(LibcameraCamera, MissingCameraIsNamedWithTheCamerasPresent) {
  const std::shared_ptr<libcamera::CameraManager> m = manager();
  ASSERT_NE(m, nullptr);
  const std::string present = describeLibcameraCameras(*m);
  for (const std::string& id : libcameraCameraIds(*m)) {
    ASSERT_NE(id, "imx219") << "a camera really has this id; the test needs another";
  }
  LibcameraCameraConfig config;
  config.camera_id = "libcamera:imx219";
  std::string error;
  EXPECT_EQ(LibcameraCamera::open(config, &error), nullptr);
  EXPECT_TRUE(contains(error, "libcamera camera 'imx219' not found"));
  EXPECT_TRUE(contains(error, "cameras present: " + present));
  std::printf("  %s\n", error.c_str());

  // findLibcameraCamera directly, with and without the prefix.
  EXPECT_EQ(findLibcameraCamera(*m, "imx219", &error), nullptr);
  EXPECT_TRUE(contains(error, "'imx219' not found"));
  // An index past the end is not found either (and is named as given).
  const std::string past_end = std::to_string(libcameraCameraIds(*m).size());
  config.camera_id = past_end;
  EXPECT_EQ(LibcameraCamera::open(config, &error), nullptr);
  EXPECT_TRUE(contains(error, "libcamera camera '" + past_end + "' not found"));
  EXPECT_EQ(LibcameraCamera::open(config, nullptr), nullptr);
}

TEST(LibcameraCamera, NoCameraHereMeansNone) {
  const std::shared_ptr<libcamera::CameraManager> m = manager();
  ASSERT_NE(m, nullptr);
  if (!m->cameras().empty()) GTEST_SKIP() << "libcamera cameras are present";
  LibcameraCameraConfig config;
  config.camera_id = "0";
  std::string error;
  EXPECT_EQ(LibcameraCamera::open(config, &error), nullptr);
  EXPECT_EQ(error, "libcamera camera '0' not found; cameras present: none");
}

TEST(LibcameraCamera, InvalidConfigIsRefusedBeforeTheCameraIsLookedFor) {
  LibcameraCameraConfig config;
  config.camera_id = "libcamera:imx219";
  config.width = 0;
  std::string error;
  EXPECT_EQ(LibcameraCamera::open(config, &error), nullptr);
  EXPECT_EQ(error, "libcamera config: width must be in [1, 16384], got 0");
}

TEST(LibcameraCameraConfig, DefaultIsValid) { EXPECT_EQ(LibcameraCameraConfig{}.validate(), ""); }

TEST(LibcameraCameraConfig, NamesTheFirstBadField) {
  struct Case {
    void (*change)(LibcameraCameraConfig*);
    const char* expected;
  };
  const Case cases[] = {
      {[](LibcameraCameraConfig* c) { c->camera_id = ""; }, "camera_id is empty"},
      {[](LibcameraCameraConfig* c) { c->camera_id = "libcamera:"; }, "camera_id is empty"},
      {[](LibcameraCameraConfig* c) { c->pixel_format = "H264"; },
       "pixel_format: pixel format 'H264' is not a known pixel format name"},
      {[](LibcameraCameraConfig* c) { c->pixel_format = "Z16"; },
       "pixel_format: pixel format 'Z16' has no libcamera stream format"},
      {[](LibcameraCameraConfig* c) { c->width = -640; }, "width must be in [1, 16384], got -640"},
      {[](LibcameraCameraConfig* c) { c->height = 20000; },
       "height must be in [1, 16384], got 20000"},
      {[](LibcameraCameraConfig* c) { c->width = 641; }, "width must be even for YUYV, got 641"},
      {[](LibcameraCameraConfig* c) {
         c->pixel_format = "NV12";
         c->height = 479;
       },
       "height must be even for NV12, got 479"},
      {[](LibcameraCameraConfig* c) { c->rate_hz = -1.0; },
       "rate_hz must be in [0, 1000] (0 = the camera's rate), got -1"},
      {[](LibcameraCameraConfig* c) { c->rate_hz = std::numeric_limits<double>::quiet_NaN(); },
       "rate_hz must be in [0, 1000]"},
      {[](LibcameraCameraConfig* c) { c->buffer_count = 0; },
       "buffer_count must be in [1, 32], got 0"},
      {[](LibcameraCameraConfig* c) { c->buffer_count = 33; },
       "buffer_count must be in [1, 32], got 33"},
      {[](LibcameraCameraConfig* c) { c->exposure_us = 0; }, "exposure_us must be > 0"},
      {[](LibcameraCameraConfig* c) { c->analogue_gain = -2.0; },
       "analogue_gain must be finite and > 0"},
      {[](LibcameraCameraConfig* c) { c->analogue_gain = std::numeric_limits<double>::infinity(); },
       "analogue_gain must be finite and > 0"},
  };
  for (const Case& c : cases) {
    LibcameraCameraConfig config;
    c.change(&config);
    const std::string message = config.validate();
    EXPECT_TRUE(contains(message, c.expected)) << message;
  }
  // Odd sizes are fine where the format allows them; 0 Hz keeps the camera's rate.
  LibcameraCameraConfig odd;
  odd.pixel_format = "GREY";
  odd.width = 641;
  odd.height = 479;
  odd.rate_hz = 0.0;
  odd.exposure_us = 10000;
  odd.analogue_gain = 1.0;
  EXPECT_EQ(odd.validate(), "");
}

// Streams a few frames from the first camera present, if any.
TEST(LibcameraCamera, StreamsFramesFromARealCamera) {
  const std::shared_ptr<libcamera::CameraManager> m = manager();
  ASSERT_NE(m, nullptr);
  if (m->cameras().empty()) GTEST_SKIP() << "no libcamera camera present";
  LibcameraCameraConfig config;
  config.camera_id = "0";
  std::string error;
  std::unique_ptr<LibcameraCamera> camera = LibcameraCamera::open(config, &error);
  if (camera == nullptr) {
    // The camera may not offer YUYV 640x480: the message lists what it offers.
    GTEST_SKIP() << "camera 0 cannot stream the default config: " << error;
  }
  ASSERT_TRUE(camera->start(&error)) << error;
  int frames = 0;
  int64_t last_ns = 0;
  for (int attempt = 0; attempt < 30 && frames < 5; ++attempt) {
    const LibcameraCamera::WaitResult result =
        camera->waitFrame(std::chrono::seconds(2), [&](const LibcameraFrame& frame) {
          GrayImage gray;
          EXPECT_TRUE(toGray(frame.image, &gray)) << toGray(frame.image, &gray).message;
          EXPECT_GT(frame.monotonic_ns, last_ns);
          last_ns = frame.monotonic_ns;
          ++frames;
        });
    ASSERT_NE(result.status, LibcameraCamera::WaitStatus::kTimeout);
    ASSERT_NE(result.status, LibcameraCamera::WaitStatus::kError) << result.message;
  }
  EXPECT_EQ(frames, 5);
  camera->stop();
  EXPECT_FALSE(camera->running());
  ASSERT_TRUE(camera->start(&error)) << error;  // restartable
}

}  // namespace
}  // namespace cblox
