#include "drivers/v4l2/v4l2_device.h"

#include <linux/videodev2.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/pixel/pixel_convert.h"
#include "drivers/v4l2/v4l2_controls.h"
#include "drivers/v4l2/v4l2_formats.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> videoDevices() {
  std::vector<std::string> devices;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/dev", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) == 0) devices.push_back(entry.path().string());
  }
  std::sort(devices.begin(), devices.end());
  return devices;
}

// ---- Without a device

TEST(V4l2DeviceTest, MissingDeviceIsNamed) {
  std::string error;
  EXPECT_EQ(V4l2Device::open("/dev/video99", &error), nullptr);
  EXPECT_EQ(error, "/dev/video99: no such device");
}

TEST(V4l2DeviceTest, NonVideoFilesAreNotV4l2Devices) {
  std::string error;
  EXPECT_EQ(V4l2Device::open("/dev/null", &error), nullptr);
  EXPECT_EQ(error.rfind("/dev/null: not a V4L2 device (VIDIOC_QUERYCAP: ", 0), 0u) << error;

  const fs::path file = fs::temp_directory_path() / "cblox_v4l2_not_a_device";
  std::ofstream(file) << "frames";
  EXPECT_EQ(V4l2Device::open(file.string(), &error), nullptr);
  EXPECT_NE(error.find("not a V4L2 device"), std::string::npos) << error;
  fs::remove(file);
}

TEST(V4l2FormatsTest, DescribesFormatsSizesAndRates) {
  V4l2FormatInfo yuyv;
  yuyv.fourcc = V4L2_PIX_FMT_YUYV;
  yuyv.description = "YUYV 4:2:2";
  V4l2FrameSize vga;
  vga.width = 640;
  vga.height = 480;
  vga.rates_hz = {30.0, 15.0, 7.5};
  V4l2FrameSize hd;
  hd.width = 1280;
  hd.height = 720;
  hd.rates_hz = {10.0};
  yuyv.sizes = {vga, hd};

  V4l2FormatInfo mjpeg;
  mjpeg.fourcc = V4L2_PIX_FMT_MJPEG;
  mjpeg.description = "Motion-JPEG";
  mjpeg.compressed = true;
  V4l2FrameSize ntsc;
  ntsc.width = 720;
  ntsc.height = 480;
  ntsc.rates_hz = {29.97};
  mjpeg.sizes = {ntsc};

  V4l2FormatInfo rgb;
  rgb.fourcc = V4L2_PIX_FMT_RGB24;
  rgb.description = "RGB3";
  rgb.emulated = true;
  V4l2FrameSize range;
  range.stepwise = true;
  range.min_width = 16;
  range.min_height = 16;
  range.width = 1920;
  range.height = 1080;
  range.step_width = 2;
  range.step_height = 2;
  range.min_rate_hz = 1.0;
  range.max_rate_hz = 60.0;
  rgb.sizes = {range};

  V4l2FormatInfo h264;
  h264.fourcc = V4L2_PIX_FMT_H264;
  h264.description = "H.264";
  h264.compressed = true;

  EXPECT_EQ(describeFormats({yuyv, mjpeg, rgb, h264}),
            "YUYV (YUYV 4:2:2): 640x480 @ 30/15/7.5 Hz, 1280x720 @ 10 Hz\n"
            "MJPG (Motion-JPEG, compressed): 720x480 @ 29.97 Hz\n"
            "RGB3 (RGB3, emulated): 16x16..1920x1080 step 2x2 @ 1-60 Hz\n"
            "H264 (H.264, compressed, not supported by cblox): (sizes not listed)");
  EXPECT_EQ(describeFormats({}), "(no formats)");
  EXPECT_EQ(formatRateHz(30.0), "30");
  EXPECT_EQ(formatRateHz(1.0 / 0.0333667), "29.97");
}

TEST(V4l2ControlsTest, NamesAndRanges) {
  EXPECT_EQ(controlIdFromName("exposure_absolute"), V4L2_CID_EXPOSURE_ABSOLUTE);
  EXPECT_EQ(controlIdFromName("exposure_auto"), V4L2_CID_EXPOSURE_AUTO);
  EXPECT_EQ(controlIdFromName("gain"), V4L2_CID_GAIN);
  EXPECT_EQ(controlIdFromName("brightness"), std::nullopt);
  const V4l2ControlRange range{3, 2047, 1, 250};
  EXPECT_EQ(checkControlValue("exposure_absolute", 3, range), "");
  EXPECT_EQ(checkControlValue("exposure_absolute", 2047, range), "");
  EXPECT_EQ(checkControlValue("exposure_absolute", 2, range),
            "exposure_absolute 2 is out of range [3, 2047]");
  EXPECT_EQ(checkControlValue("gain", 5, V4l2ControlRange{0, 100, 2, 0}),
            "gain 5 is not 0 + a multiple of 2");
  EXPECT_EQ(checkControlValue("gain", 6, V4l2ControlRange{0, 100, 2, 0}), "");
}

// ---- With a device (skipped where there is none)

TEST(V4l2DeviceTest, ListsFormatsAndStreamsTenFrames) {
  const std::vector<std::string> paths = videoDevices();
  if (paths.empty()) GTEST_SKIP() << "no /dev/video* device (vivid module not loadable here)";
  for (const std::string& path : paths) {
    std::string error;
    std::unique_ptr<V4l2Device> device = V4l2Device::open(path, &error);
    if (!device) {
      std::cout << "skipping " << error << "\n";  // metadata nodes, busy cameras
      continue;
    }
    std::vector<V4l2FormatInfo> formats;
    ASSERT_TRUE(device->listFormats(&formats, &error)) << error;
    std::cout << path << " (" << device->card() << "):\n" << describeFormats(formats) << "\n";
    // The first convertible format with a discrete size.
    std::optional<V4l2StreamConfig> config;
    for (const V4l2FormatInfo& format : formats) {
      const std::optional<PixelFormat> pixel = pixelFormatFromFourcc(format.fourcc);
      if (!pixel || format.sizes.empty() || format.sizes.front().stepwise) continue;
      config =
          V4l2StreamConfig{*pixel, format.sizes.front().width, format.sizes.front().height, 0.0, 4};
      break;
    }
    if (!config) continue;
    ASSERT_TRUE(device->configure(*config, &error)) << error;
    int frames = 0;
    int64_t last_timestamp = 0;
    for (int i = 0; i < 30 && frames < 10; ++i) {
      V4l2Frame frame;
      const V4l2Status status = device->dequeue(2000, &frame, &error);
      ASSERT_NE(status, V4l2Status::kDeviceLost) << error;
      ASSERT_NE(status, V4l2Status::kError) << error;
      if (status != V4l2Status::kOk || frame.corrupt) continue;
      EXPECT_EQ(frame.image.width, config->width);
      EXPECT_GT(frame.timestamp_ns, last_timestamp);
      last_timestamp = frame.timestamp_ns;
      if (config->format != PixelFormat::kZ16) {
        GrayImage gray;
        const ConvertResult converted = toGray(frame.image, &gray);
        EXPECT_TRUE(converted) << converted.message;
      }
      ASSERT_TRUE(device->requeue(&error)) << error;
      ++frames;
    }
    EXPECT_EQ(frames, 10) << path;
    return;
  }
  GTEST_SKIP() << "no /dev/video* device streams a format cblox converts";
}

}  // namespace
}  // namespace cblox
