#include "drivers/dataset/tum_rgbd_reader.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test/test_support/contains.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

using test::contains;
using test::containsLine;

std::string stamp(double t) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6f", t);
  return buffer;
}

// Depth frames (seconds) and colour frames of the synthetic sequence. Association as TUM's
// associate.py with 0.02 s: 1.000-1.005, 1.033-1.040, 1.066-1.060, 1.200 none; 2.010-2.008
// (0.002) is taken first, so 2.000 gets 1.985 (0.015) although 2.008 is nearer to it; 0.990
// stays unused.
const std::vector<double> kDepthTimes = {1.000, 1.033, 1.066, 1.200, 2.000, 2.010};
const std::vector<double> kRgbTimes = {0.990, 1.005, 1.040, 1.060, 1.985, 2.008};
// Index into kRgbTimes associated with each depth frame, -1 for none.
const std::vector<int> kExpectedRgb = {1, 2, 3, -1, 4, 5};

// Writes a small valid TUM RGB-D folder (8x6 images) into a fresh temporary directory.
class TumRgbdReaderTest : public testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(dir_.path() / "rgb");
    fs::create_directories(dir_.path() / "depth");
    std::string depth_list = "# depth maps\n# file: 'synthetic.bag'\n# timestamp filename\n";
    for (size_t i = 0; i < kDepthTimes.size(); ++i) {
      const std::string name = "depth/" + stamp(kDepthTimes[i]) + ".png";
      depth_list += stamp(kDepthTimes[i]) + " " + name + "\n";
      writeDepth(name, static_cast<int>(i));
    }
    std::string rgb_list = "# color images\n# file: 'synthetic.bag'\n# timestamp filename\n";
    for (size_t k = 0; k < kRgbTimes.size(); ++k) {
      const std::string name = "rgb/" + stamp(kRgbTimes[k]) + ".png";
      rgb_list += stamp(kRgbTimes[k]) + " " + name + "\n";
      writeColor(name, static_cast<int>(k));
    }
    dir_.write("depth.txt", depth_list);
    dir_.write("rgb.txt", rgb_list);
  }
  // Depth in TUM units (5000 per metre): 5000 at (0,0), 0 at (1,0), 12345 at (2,0),
  // 65535 at (3,0), 1000 + frame at (4,4), 7500 elsewhere.
  void writeDepth(const std::string& name, int frame) const {
    cv::Mat depth(kHeight, kWidth, CV_16UC1, cv::Scalar(7500));
    depth.at<uint16_t>(0, 0) = 5000;
    depth.at<uint16_t>(0, 1) = 0;
    depth.at<uint16_t>(0, 2) = 12345;
    depth.at<uint16_t>(0, 3) = 65535;
    depth.at<uint16_t>(4, 4) = static_cast<uint16_t>(1000 + frame);
    ASSERT_TRUE(cv::imwrite(dir_.file(name), depth));
  }
  // Colour (RGB) (50, 100, 20 * k) everywhere except pure red at (u, v) = (2, 1).
  void writeColor(const std::string& name, int k) const {
    cv::Mat bgr(kHeight, kWidth, CV_8UC3, cv::Scalar(20 * k, 100, 50));  // B, G, R
    bgr.at<cv::Vec3b>(1, 2) = cv::Vec3b(0, 0, 255);
    ASSERT_TRUE(cv::imwrite(dir_.file(name), bgr));
  }
  std::optional<TumRgbdReader> open(std::string* error,
                                    const TumRgbdReader::Options& options = {}) const {
    return TumRgbdReader::open(dir_.path().string(), options, error);
  }
  // Expects open() to fail with a message containing every needle.
  void expectOpenFails(const std::vector<std::string>& needles,
                       const TumRgbdReader::Options& options = {}) const {
    std::string error;
    EXPECT_FALSE(open(&error, options).has_value());
    for (const std::string& needle : needles) EXPECT_TRUE(contains(error, needle));
  }

  static constexpr int kWidth = 8;
  static constexpr int kHeight = 6;
  test::TempDir dir_{"cblox_tum"};
};

TEST_F(TumRgbdReaderTest, ReadsDepthInMetresAndColourAsRgb) {
  std::string error;
  const std::optional<TumRgbdReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), kDepthTimes.size());
  EXPECT_EQ(reader->folder(), dir_.path().string());
  EXPECT_FALSE(reader->hasGroundTruth());
  EXPECT_TRUE(containsLine(reader->notes(), "no ground truth: groundtruth.txt absent"));

  TumRgbdFrame frame;
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  EXPECT_DOUBLE_EQ(frame.timestamp_s, 1.0);
  ASSERT_EQ(frame.depth.width, kWidth);
  ASSERT_EQ(frame.depth.height, kHeight);
  EXPECT_EQ(frame.depth(0, 0), 1.0f);  // 5000 units = 1 m exactly
  EXPECT_EQ(frame.depth(1, 0), 0.0f);  // 0 = invalid
  EXPECT_FLOAT_EQ(frame.depth(2, 0), 2.469f);
  EXPECT_FLOAT_EQ(frame.depth(3, 0), 13.107f);
  EXPECT_EQ(frame.depth(5, 5), 1.5f);
  EXPECT_FLOAT_EQ(frame.depth(4, 4), 0.2f);  // 1000 units, frame 0
  ASSERT_EQ(frame.color.width, kWidth);
  ASSERT_EQ(frame.color.height, kHeight);
  EXPECT_EQ(frame.color(2, 1), (Color{255, 0, 0}));  // pure red stays red
  EXPECT_EQ(frame.color(0, 0), (Color{50, 100, 20}));
  EXPECT_FALSE(frame.T_G_C.has_value());

  // Another depth scale.
  TumRgbdReader::Options options;
  options.depth_scale = 0.001;
  const std::optional<TumRgbdReader> millimetres = open(&error, options);
  ASSERT_TRUE(millimetres.has_value()) << error;
  ASSERT_TRUE(millimetres->read(0, &frame, &error)) << error;
  EXPECT_EQ(frame.depth(0, 0), 5.0f);

  EXPECT_FALSE(reader->read(kDepthTimes.size(), &frame, &error));
  EXPECT_TRUE(contains(error, "out of range"));
}

TEST_F(TumRgbdReaderTest, AssociatesNearestColourGreedilyAsAssociatePy) {
  std::string error;
  const std::optional<TumRgbdReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), kDepthTimes.size());
  for (size_t i = 0; i < reader->size(); ++i) {
    TumRgbdFrame frame;
    ASSERT_TRUE(reader->read(i, &frame, &error)) << error;
    EXPECT_DOUBLE_EQ(reader->timestamp(i), kDepthTimes[i]);
    EXPECT_FLOAT_EQ(frame.depth(4, 4), (1000.0f + static_cast<float>(i)) / 5000.0f);  // its file
    if (kExpectedRgb[i] < 0) {
      EXPECT_TRUE(frame.color.empty()) << i;
      EXPECT_FALSE(frame.color_timestamp_s.has_value()) << i;
      continue;
    }
    ASSERT_TRUE(frame.color_timestamp_s.has_value()) << i;
    EXPECT_DOUBLE_EQ(*frame.color_timestamp_s, kRgbTimes[static_cast<size_t>(kExpectedRgb[i])])
        << i;
    ASSERT_FALSE(frame.color.empty()) << i;
    EXPECT_EQ(frame.color(0, 0).b, 20 * kExpectedRgb[i]) << i;
  }
  ASSERT_EQ(reader->skipped().size(), 1u);
  EXPECT_TRUE(containsLine(
      reader->skipped(),
      "depth/1.200000.png: no colour image within 0.02 s, frame 1.200000 played without colour"));
  EXPECT_TRUE(containsLine(reader->notes(), "1 of 6 frames have no colour image"));
  EXPECT_TRUE(containsLine(reader->notes(), "1 of 6 colour images are not associated"));

  // A tighter window drops the 0.015 s pair and the 0.007 s one stays.
  TumRgbdReader::Options options;
  options.max_association_difference_s = 0.01;
  const std::optional<TumRgbdReader> tight = open(&error, options);
  ASSERT_TRUE(tight.has_value()) << error;
  TumRgbdFrame frame;
  ASSERT_TRUE(tight->read(4, &frame, &error)) << error;
  EXPECT_TRUE(frame.color.empty());
  ASSERT_TRUE(tight->read(1, &frame, &error)) << error;
  EXPECT_FALSE(frame.color.empty());
  EXPECT_TRUE(containsLine(tight->notes(), "2 of 6 frames have no colour image"));
}

TEST_F(TumRgbdReaderTest, InterpolatesGroundTruth) {
  // 0.96 identity, 1.04 (x = 1, 0.2 rad about z), 1.10 (x = 2), then a 0.15 s gap
  // (1.90 .. 2.05): frames 1.000, 1.033, 1.066 have poses; 1.200 is outside; 2.000, 2.010 are
  // in the gap.
  const double half = 0.1;
  dir_.write("groundtruth.txt",
             "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n"
             "0.96 0 0 0 0 0 0 1\n"
             "1.04 1 0 0 0 0 " +
                 std::to_string(std::sin(half)) + " " + std::to_string(std::cos(half)) +
                 "\n1.10 2 0 0 0 0 0 1\n1.90 3 0 0 0 0 0 1\n"
                 "2.05 4 0 0 0 0 0 1\n");
  std::string error;
  const std::optional<TumRgbdReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  EXPECT_TRUE(reader->hasGroundTruth());
  EXPECT_TRUE(containsLine(reader->notes(), "3 of 6 frames have no ground truth"));
  const Transformationd A;
  const Transformationd B(Eigen::Quaterniond(std::stod(std::to_string(std::cos(half))), 0, 0,
                                             std::stod(std::to_string(std::sin(half)))),
                          Eigen::Vector3d(1, 0, 0));
  TumRgbdFrame frame;
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  ASSERT_TRUE(frame.T_G_C.has_value());
  const Transformationd expected = Transformationd::interpolate(A, B, 0.5);
  EXPECT_TRUE(frame.T_G_C->isApprox(expected, 1e-9)) << *frame.T_G_C << " vs " << expected;
  EXPECT_NEAR(frame.T_G_C->rotation().angularDistance(A.rotation()), 0.1, 1e-6);
  for (const size_t i : {1u, 2u}) {
    ASSERT_TRUE(reader->read(i, &frame, &error)) << error;
    EXPECT_TRUE(frame.T_G_C.has_value()) << i;
  }
  for (const size_t i : {3u, 4u, 5u}) {
    ASSERT_TRUE(reader->read(i, &frame, &error)) << error;
    EXPECT_FALSE(frame.T_G_C.has_value()) << i;
  }

  // A larger allowed gap covers the frames in the 0.15 s gap.
  TumRgbdReader::Options options;
  options.groundtruth_max_gap_s = 0.2;
  const std::optional<TumRgbdReader> wide = open(&error, options);
  ASSERT_TRUE(wide.has_value()) << error;
  ASSERT_TRUE(wide->read(4, &frame, &error)) << error;
  ASSERT_TRUE(frame.T_G_C.has_value());
  EXPECT_NEAR(frame.T_G_C->translation().x(), 3.0 + 0.1 / 0.15, 1e-9);
  EXPECT_TRUE(containsLine(wide->notes(), "1 of 6 frames have no ground truth"));

  // Malformed ground truth: readTumTrajectory's file:line message.
  dir_.write("groundtruth.txt", "0.96 0 0 0 0 0 0 1\n1.04 1 0 0 0 0 0\n");
  expectOpenFails({dir_.file("groundtruth.txt") + ":2:", "expected 8 numbers"});
}

TEST_F(TumRgbdReaderTest, IntrinsicsFromOptionsFileOrDefault) {
  std::string error;
  std::optional<TumRgbdReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  PinholeIntrinsics in = reader->intrinsics();
  EXPECT_EQ(in.fx, 525.0);
  EXPECT_EQ(in.fy, 525.0);
  EXPECT_EQ(in.cx, 319.5);
  EXPECT_EQ(in.cy, 239.5);
  EXPECT_EQ(in.width, kWidth);
  EXPECT_EQ(in.height, kHeight);
  EXPECT_TRUE(containsLine(reader->notes(), "using TUM's default fx = fy = 525"));

  dir_.write("camera-intrinsics.txt", "500 0 4\n0 510 3\n0 0 1\n");
  reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  in = reader->intrinsics();
  EXPECT_EQ(in.fx, 500.0);
  EXPECT_EQ(in.fy, 510.0);
  EXPECT_EQ(in.cx, 4.0);
  EXPECT_EQ(in.cy, 3.0);
  EXPECT_EQ(in.width, kWidth);
  EXPECT_EQ(in.height, kHeight);
  EXPECT_FALSE(containsLine(reader->notes(), "default"));

  TumRgbdReader::Options options;
  options.intrinsics = PinholeIntrinsics{400, 401, 3.5, 2.5, 0, 0};
  reader = open(&error, options);
  ASSERT_TRUE(reader.has_value()) << error;
  in = reader->intrinsics();
  EXPECT_EQ(in.fx, 400.0);
  EXPECT_EQ(in.fy, 401.0);
  EXPECT_EQ(in.width, kWidth);  // 0 x 0: from the first depth image
  EXPECT_EQ(in.height, kHeight);

  // Explicit size that differs from the images: read() rejects the depth image.
  options.intrinsics = PinholeIntrinsics{400, 401, 3.5, 2.5, 640, 480};
  reader = open(&error, options);
  ASSERT_TRUE(reader.has_value()) << error;
  TumRgbdFrame frame;
  EXPECT_FALSE(reader->read(0, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file("depth/1.000000.png")));
  EXPECT_TRUE(contains(error, "size 8x6 does not match the intrinsics' 640x480"));

  options.intrinsics = PinholeIntrinsics{-400, 401, 3.5, 2.5, 0, 0};
  expectOpenFails({"TumRgbdReader::Options: intrinsics: fx must be > 0"}, options);

  dir_.write("camera-intrinsics.txt", "500 0 4\n0 510 3\n");
  expectOpenFails({dir_.file("camera-intrinsics.txt"), "expected 9 numbers"});
  dir_.write("camera-intrinsics.txt", "500 0 4\n0 510 3\n1 0 1\n");
  expectOpenFails({dir_.file("camera-intrinsics.txt")});
  dir_.write("camera-intrinsics.txt", "0 0 4\n0 510 3\n0 0 1\n");
  expectOpenFails({dir_.file("camera-intrinsics.txt"), "fx must be > 0"});
}

TEST_F(TumRgbdReaderTest, RejectsMalformedLists) {
  const std::string header = "# color images\n";
  dir_.write("rgb.txt", header + "1.0 rgb/a.png\n1.1 rgb/b.png extra\n");
  expectOpenFails({dir_.file("rgb.txt") + ":3:", "expected 'timestamp filename'"});

  dir_.write("rgb.txt", header + "1.0 rgb/a.png\n\n1.1x rgb/b.png\n");
  expectOpenFails({dir_.file("rgb.txt") + ":4:", "'1.1x' is not a finite number"});

  dir_.write("rgb.txt", header + "nan rgb/a.png\n");
  expectOpenFails({dir_.file("rgb.txt") + ":2:", "not a finite number"});

  dir_.write("rgb.txt", header);
  dir_.write("depth.txt", "1.0 depth/1.000000.png\r\n1.0 depth/1.033000.png\r\n");
  expectOpenFails({dir_.file("depth.txt") + ":2:", "does not increase"});

  dir_.write("depth.txt", "1.0\n");
  expectOpenFails({dir_.file("depth.txt") + ":1:", "expected 'timestamp filename', got '1.0'"});

  fs::remove(dir_.file("depth.txt"));
  expectOpenFails({dir_.file("depth.txt"), "missing"});
  fs::remove(dir_.file("rgb.txt"));
  expectOpenFails({"missing"});
}

TEST_F(TumRgbdReaderTest, SkipsMissingImages) {
  fs::remove(dir_.file("depth/1.033000.png"));
  fs::remove(dir_.file("rgb/1.005000.png"));
  std::string error;
  const std::optional<TumRgbdReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), kDepthTimes.size() - 1);
  EXPECT_DOUBLE_EQ(reader->timestamp(1), 1.066);
  EXPECT_TRUE(
      containsLine(reader->skipped(), "depth/1.033000.png: missing, depth frame 1.033000 skipped"));
  EXPECT_TRUE(
      containsLine(reader->skipped(), "rgb/1.005000.png: missing, colour image 1.005000 skipped"));
  EXPECT_TRUE(containsLine(reader->notes(), "2 listed images are missing on disk"));
  // Without 1.005, depth 1.000 takes the next nearest colour image, 0.990.
  TumRgbdFrame frame;
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  ASSERT_TRUE(frame.color_timestamp_s.has_value());
  EXPECT_DOUBLE_EQ(*frame.color_timestamp_s, 0.990);

  for (const double t : kDepthTimes) fs::remove(dir_.file("depth/" + stamp(t) + ".png"));
  expectOpenFails({dir_.file("depth.txt"), "no depth image (6 listed, none found on disk)"});
}

TEST_F(TumRgbdReaderTest, RejectsBadImages) {
  // 8-bit depth: rejected by read(), and by open() for the first frame (it sets the size).
  ASSERT_TRUE(cv::imwrite(dir_.file("depth/1.066000.png"),
                          cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(100))));
  std::string error;
  const std::optional<TumRgbdReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  TumRgbdFrame frame;
  frame.timestamp_s = -1.0;
  EXPECT_FALSE(reader->read(2, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file("depth/1.066000.png")));
  EXPECT_TRUE(contains(error, "16-bit single-channel PNG, got 8-bit with 1 channel(s)"));
  EXPECT_EQ(frame.timestamp_s, -1.0);  // untouched

  // Depth of another size.
  ASSERT_TRUE(cv::imwrite(dir_.file("depth/2.000000.png"),
                          cv::Mat(kHeight, kWidth + 1, CV_16UC1, cv::Scalar(100))));
  EXPECT_FALSE(reader->read(4, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file("depth/2.000000.png")));
  EXPECT_TRUE(contains(error, "9x6"));

  // Colour of another size; colour deleted after open().
  ASSERT_TRUE(cv::imwrite(dir_.file("rgb/2.008000.png"),
                          cv::Mat(kHeight + 1, kWidth, CV_8UC3, cv::Scalar(1, 2, 3))));
  EXPECT_FALSE(reader->read(5, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file("rgb/2.008000.png")));
  EXPECT_TRUE(contains(error, "size 8x7 does not match the depth image's 8x6"));
  fs::remove(dir_.file("rgb/1.005000.png"));
  EXPECT_FALSE(reader->read(0, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file("rgb/1.005000.png")));
  EXPECT_TRUE(contains(error, "missing"));
  ASSERT_TRUE(reader->read(1, &frame, &error)) << error;  // others still fine

  ASSERT_TRUE(cv::imwrite(dir_.file("depth/1.000000.png"),
                          cv::Mat(kHeight, kWidth, CV_16UC3, cv::Scalar(1, 2, 3))));
  expectOpenFails({dir_.file("depth/1.000000.png"), "16-bit single-channel", "3 channel"});
}

TEST_F(TumRgbdReaderTest, RejectsBadOptionsAndFolders) {
  TumRgbdReader::Options options;
  options.depth_scale = 0.0;
  expectOpenFails({"depth_scale must be > 0"}, options);
  options = {};
  options.max_association_difference_s = -1.0;
  expectOpenFails({"max_association_difference_s must be > 0"}, options);
  options = {};
  options.groundtruth_max_gap_s = std::nan("");
  expectOpenFails({"groundtruth_max_gap_s must be > 0"}, options);
  std::string error;
  EXPECT_FALSE(TumRgbdReader::open(dir_.file("nope"), {}, &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file("nope")));
  EXPECT_FALSE(TumRgbdReader::open(dir_.file("nope"), {}, nullptr).has_value());
}

}  // namespace
}  // namespace cblox
