#include "drivers/dataset/seven_scenes_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
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

const std::string kSevenScenesDir = std::string(CBLOX_SHARED_DATA_DIR) + "/7scenes-rgbd-50";

using test::contains;

TEST(SevenScenesReaderTest, ParsesRealData) {
  if (!fs::is_directory(kSevenScenesDir)) {
    GTEST_SKIP() << "shared data not present at " << kSevenScenesDir
                 << " (only available next to the project checkout)";
  }
  std::string error;
  const std::optional<SevenScenesReader> reader = SevenScenesReader::open(kSevenScenesDir, &error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), 50u);
  EXPECT_EQ(reader->frameIndex(0), 150);
  EXPECT_EQ(reader->frameIndex(49), 199);
  const PinholeIntrinsics& in = reader->depthIntrinsics();
  EXPECT_DOUBLE_EQ(in.fx, 585.0);
  EXPECT_DOUBLE_EQ(in.fy, 585.0);
  EXPECT_DOUBLE_EQ(in.cx, 320.0);
  EXPECT_DOUBLE_EQ(in.cy, 240.0);
  EXPECT_EQ(in.width, 640);
  EXPECT_EQ(in.height, 480);

  SevenScenesFrame frame;
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  EXPECT_EQ(frame.index, 150);

  // Pose equals the file's matrix.
  std::ifstream pose_file(kSevenScenesDir + "/frame-000150.pose.txt");
  Eigen::Matrix4d expected;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) ASSERT_TRUE(pose_file >> expected(r, c));
  }
  // The translation is kept exactly. KinectFusion's rotations are orthonormal only to ~1e-4
  // (this one is scaled by ~0.99994), and SE3 stores the nearest rotation, so the rotation
  // entries match to that level.
  const Eigen::Matrix3d R_file = expected.topLeftCorner<3, 3>();
  const double non_orthonormality =
      (R_file.transpose() * R_file - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  EXPECT_LT(non_orthonormality, 1e-3);
  EXPECT_EQ(frame.T_G_C.translation(), Eigen::Vector3d(expected.topRightCorner<3, 1>()));
  EXPECT_LT((frame.T_G_C.rotationMatrix() - R_file).cwiseAbs().maxCoeff(),
            std::max(1e-6, non_orthonormality))
      << frame.T_G_C.matrix() << "\nvs\n"
      << expected;
  RecordProperty("pose_non_orthonormality", std::to_string(non_orthonormality));
  EXPECT_NEAR(expected(0, 3), -0.91287065, 1e-9);  // sanity: the file is what we think

  // Depth in metres: compare with the raw 16-bit value read by OpenCV directly.
  const cv::Mat raw = cv::imread(kSevenScenesDir + "/frame-000150.depth.png", cv::IMREAD_ANYDEPTH);
  ASSERT_EQ(raw.type(), CV_16UC1);
  ASSERT_EQ(frame.depth.width, 640);
  ASSERT_EQ(frame.depth.height, 480);
  const uint16_t centre_mm = raw.at<uint16_t>(240, 320);
  ASSERT_GT(centre_mm, 0) << "expected a valid depth at the centre pixel";
  ASSERT_LT(centre_mm, 65535);
  EXPECT_FLOAT_EQ(frame.depth(320, 240), centre_mm / 1000.0f);
  int invalid = 0;
  for (int v = 0; v < raw.rows; ++v) {
    for (int u = 0; u < raw.cols; ++u) {
      const uint16_t mm = raw.at<uint16_t>(v, u);
      if (mm == 0 || mm == 65535) {
        ++invalid;
        ASSERT_EQ(frame.depth(u, v), 0.0f);
      } else {
        ASSERT_FLOAT_EQ(frame.depth(u, v), mm / 1000.0f);
      }
    }
  }
  RecordProperty("invalid_depth_pixels", invalid);

  // Colour is RGB (OpenCV reads BGR).
  const cv::Mat bgr = cv::imread(kSevenScenesDir + "/frame-000150.color.png", cv::IMREAD_COLOR);
  ASSERT_EQ(frame.color.width, bgr.cols);
  const cv::Vec3b px = bgr.at<cv::Vec3b>(100, 200);
  EXPECT_EQ(frame.color(200, 100), (Color{px[2], px[1], px[0]}));

  // Every frame reads (poses pass validation); out of range is an error.
  for (size_t i = 0; i < reader->size(); ++i) {
    ASSERT_TRUE(reader->read(i, &frame, &error)) << error;
    EXPECT_EQ(frame.index, 150 + static_cast<int64_t>(i));
  }
  EXPECT_FALSE(reader->read(50, &frame, &error));
}

// Writes a small valid 7-Scenes folder into a fresh temporary directory.
class SevenScenesMalformedTest : public testing::Test {
 protected:
  void SetUp() override {
    writeIntrinsics();
    for (const int n : {3, 10, 7}) writeFrame(n);
  }
  static std::string frameName(int n, const std::string& suffix) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "frame-%06d%s", n, suffix.c_str());
    return buf;
  }

  void writeIntrinsics() const { dir_.write("camera-intrinsics.txt", "10 0 4\n0 10 3\n0 0 1\n"); }
  void writeFrame(int n) const {
    cv::Mat depth(kHeight, kWidth, CV_16UC1, cv::Scalar(1500));
    depth.at<uint16_t>(0, 0) = 0;
    depth.at<uint16_t>(0, 1) = 65535;
    depth.at<uint16_t>(1, 2) = static_cast<uint16_t>(n);
    ASSERT_TRUE(cv::imwrite(dir_.file(frameName(n, ".depth.png")), depth));
    cv::Mat color(kHeight, kWidth, CV_8UC3, cv::Scalar(10, 20, 30));  // B, G, R
    ASSERT_TRUE(cv::imwrite(dir_.file(frameName(n, ".color.png")), color));
    dir_.write(frameName(n, ".pose.txt"),
               "0 -1 0 1\n1 0 0 2\n0 0 1 " + std::to_string(n) + "\n0 0 0 1\n");
  }

  static constexpr int kWidth = 8;
  static constexpr int kHeight = 6;
  test::TempDir dir_{"cblox_7scenes"};
};

TEST_F(SevenScenesMalformedTest, ValidFolderReadsWithGapsSorted) {
  std::string error;
  const auto reader = SevenScenesReader::open(dir_.path().string(), &error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), 3u);
  EXPECT_EQ(reader->frameIndex(0), 3);
  EXPECT_EQ(reader->frameIndex(1), 7);
  EXPECT_EQ(reader->frameIndex(2), 10);
  EXPECT_EQ(reader->depthIntrinsics().width, kWidth);
  EXPECT_EQ(reader->depthIntrinsics().height, kHeight);
  EXPECT_DOUBLE_EQ(reader->depthIntrinsics().fx, 10.0);
  SevenScenesFrame frame;
  ASSERT_TRUE(reader->read(1, &frame, &error)) << error;
  EXPECT_EQ(frame.index, 7);
  EXPECT_NEAR((frame.T_G_C.translation() - Eigen::Vector3d(1, 2, 7)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((frame.T_G_C * Eigen::Vector3d::UnitX() - Eigen::Vector3d(1, 3, 7)).norm(), 0.0,
              1e-12);
  EXPECT_EQ(frame.depth(0, 0), 0.0f);  // 0 mm: invalid
  EXPECT_EQ(frame.depth(1, 0), 0.0f);  // 65535 mm: invalid
  EXPECT_FLOAT_EQ(frame.depth(2, 1), 0.007f);
  EXPECT_FLOAT_EQ(frame.depth(5, 5), 1.5f);
  EXPECT_EQ(frame.color(3, 3), (Color{30, 20, 10}));
}

// A smooth BGR gradient, so that JPEG's error stays small and a channel swap would show.
cv::Mat gradientBgr(int width, int height) {
  cv::Mat bgr(height, width, CV_8UC3);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      bgr.at<cv::Vec3b>(v, u) =
          cv::Vec3b(static_cast<uint8_t>(40 + 10 * u), static_cast<uint8_t>(120 + 8 * v),
                    static_cast<uint8_t>(220 - 5 * u - 5 * v));
    }
  }
  return bgr;
}

TEST_F(SevenScenesMalformedTest, ReadsJpegColourLikePng) {
  // Reference: every frame with a PNG gradient.
  const cv::Mat bgr = gradientBgr(kWidth, kHeight);
  for (const int n : {3, 7, 10})
    ASSERT_TRUE(cv::imwrite(dir_.file(frameName(n, ".color.png")), bgr));
  std::string error;
  const auto png_reader = SevenScenesReader::open(dir_.path().string(), &error);
  ASSERT_TRUE(png_reader.has_value()) << error;
  std::vector<SevenScenesFrame> reference(png_reader->size());
  for (size_t i = 0; i < reference.size(); ++i) {
    ASSERT_TRUE(png_reader->read(i, &reference[i], &error)) << error;
  }

  // Frame 7 only as JPEG (a mixed folder); frame 10 as both (the PNG wins); then every frame
  // as JPEG (a whole JPEG copy).
  const std::vector<int> quality = {cv::IMWRITE_JPEG_QUALITY, 95};
  ASSERT_TRUE(cv::imwrite(dir_.file(frameName(7, ".color.jpg")), bgr, quality));
  ASSERT_TRUE(fs::remove(dir_.file(frameName(7, ".color.png"))));
  ASSERT_TRUE(cv::imwrite(dir_.file(frameName(10, ".color.jpg")), bgr, quality));
  for (const bool all_jpeg : {false, true}) {
    if (all_jpeg) {
      for (const int n : {3, 10}) {
        ASSERT_TRUE(cv::imwrite(dir_.file(frameName(n, ".color.jpg")), bgr, quality));
        ASSERT_TRUE(fs::remove(dir_.file(frameName(n, ".color.png"))));
      }
    }
    const auto reader = SevenScenesReader::open(dir_.path().string(), &error);
    ASSERT_TRUE(reader.has_value()) << error;
    ASSERT_EQ(reader->size(), 3u);
    const bool jpeg[] = {all_jpeg, true, all_jpeg};  // frames 3, 7, 10
    for (size_t i = 0; i < 3; ++i) {
      SCOPED_TRACE("frame " + std::to_string(reader->frameIndex(i)) +
                   (all_jpeg ? ", all JPEG" : ", mixed"));
      const std::string suffix = jpeg[i] ? ".color.jpg" : ".color.png";
      EXPECT_EQ(reader->colorPath(i),
                dir_.file(frameName(static_cast<int>(reader->frameIndex(i)), suffix)));
      SevenScenesFrame frame;
      ASSERT_TRUE(reader->read(i, &frame, &error)) << error;
      const SevenScenesFrame& ref = reference[i];
      EXPECT_EQ(frame.index, ref.index);
      EXPECT_EQ(frame.T_G_C.matrix(), ref.T_G_C.matrix());  // identical, not just close
      ASSERT_EQ(frame.depth.width, ref.depth.width);
      ASSERT_EQ(frame.depth.height, ref.depth.height);
      ASSERT_EQ(frame.color.width, kWidth);
      ASSERT_EQ(frame.color.height, kHeight);
      int worst = 0;
      for (int v = 0; v < kHeight; ++v) {
        for (int u = 0; u < kWidth; ++u) {
          EXPECT_EQ(frame.depth(u, v), ref.depth(u, v));
          const Color got = frame.color(u, v), want = ref.color(u, v);
          worst = std::max({worst, std::abs(got.r - want.r), std::abs(got.g - want.g),
                            std::abs(got.b - want.b)});
        }
      }
      // PNG is exact (RGB order from BGR files); JPEG at quality 95 within a few levels.
      EXPECT_EQ(ref.color(2, 1), (Color{220 - 15, 128, 60}));
      EXPECT_LE(worst, jpeg[i] ? 12 : 0);
    }
  }

  // A frame without any colour file names both spellings.
  ASSERT_TRUE(fs::remove(dir_.file(frameName(7, ".color.jpg"))));
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file(frameName(7, ".color.png")))) << error;
  EXPECT_TRUE(contains(error, ".color.jpg")) << error;
}

TEST_F(SevenScenesMalformedTest, RejectsBadPoseFiles) {
  const std::string name = frameName(7, ".pose.txt");
  const std::pair<std::string, std::string> cases[] = {
      {"0 -1 0 1\n1 0 0 2\n0 0 1 7\n0 0 0\n", "expected 16 numbers"},
      {"0 -1 0 1\n1 0 0 2\n0 0 1 7\n0 0 0 1 5\n", "expected 16 numbers"},
      {"0 -1 0 1\n1 0 0 2\n0 0 1 seven\n0 0 0 1\n", "not a number"},
      {"0 -1 0 1\n1 0 0 2\n0 0 1 7\n0 0 1 1\n", "last row"},
      {"0 -1.01 0 1\n1 0 0 2\n0 0 1 7\n0 0 0 1\n", "orthonormal"},
      {"0 -1 0 1\n1 0 0 2\n0 0 -1 7\n0 0 0 1\n", "reflection"},
      {"", "expected 16 numbers"},
  };
  for (const auto& [text, reason] : cases) {
    dir_.write(name, text);
    std::string error;
    const auto reader = SevenScenesReader::open(dir_.path().string(), &error);
    ASSERT_TRUE(reader.has_value()) << error;
    SevenScenesFrame frame;
    frame.index = -42;
    EXPECT_FALSE(reader->read(1, &frame, &error)) << text;
    EXPECT_TRUE(contains(error, dir_.file(name))) << text;
    EXPECT_TRUE(contains(error, reason)) << text;
    EXPECT_EQ(frame.index, -42);                            // untouched
    EXPECT_TRUE(reader->read(0, &frame, &error)) << error;  // other frames still fine
  }
}

TEST_F(SevenScenesMalformedTest, RejectsMissingOrBadIntrinsics) {
  fs::remove(dir_.file("camera-intrinsics.txt"));
  std::string error;
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file("camera-intrinsics.txt")));

  dir_.write("camera-intrinsics.txt", "10 0 4\n0 10 3\n");
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file("camera-intrinsics.txt")));

  dir_.write("camera-intrinsics.txt", "10 0 4\n0 10 3\n1 0 1\n");
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file("camera-intrinsics.txt")));

  dir_.write("camera-intrinsics.txt", "-10 0 4\n0 10 3\n0 0 1\n");
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file("camera-intrinsics.txt")));
  EXPECT_TRUE(contains(error, "fx"));
}

TEST_F(SevenScenesMalformedTest, RejectsEightBitDepth) {
  const cv::Mat eight_bit(kHeight, kWidth, CV_8UC1, cv::Scalar(100));
  ASSERT_TRUE(cv::imwrite(dir_.file(frameName(10, ".depth.png")), eight_bit));
  std::string error;
  const auto reader = SevenScenesReader::open(dir_.path().string(), &error);
  ASSERT_TRUE(reader.has_value()) << error;
  SevenScenesFrame frame;
  EXPECT_FALSE(reader->read(2, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file(frameName(10, ".depth.png"))));
  EXPECT_TRUE(contains(error, "16-bit single-channel"));
  EXPECT_TRUE(contains(error, "8-bit"));

  // The first frame's depth is read by open(): rejected there.
  ASSERT_TRUE(cv::imwrite(dir_.file(frameName(3, ".depth.png")), eight_bit));
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file(frameName(3, ".depth.png"))));

  // A 16-bit three-channel image is rejected too.
  const cv::Mat rgb16(kHeight, kWidth, CV_16UC3, cv::Scalar(1000, 1000, 1000));
  ASSERT_TRUE(cv::imwrite(dir_.file(frameName(3, ".depth.png")), rgb16));
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, "3 channel"));
}

TEST_F(SevenScenesMalformedTest, RejectsMismatchedSizes) {
  const cv::Mat big_color(kHeight + 2, kWidth, CV_8UC3, cv::Scalar(0, 0, 0));
  ASSERT_TRUE(cv::imwrite(dir_.file(frameName(7, ".color.png")), big_color));
  const cv::Mat big_depth(kHeight, kWidth + 1, CV_16UC1, cv::Scalar(1000));
  ASSERT_TRUE(cv::imwrite(dir_.file(frameName(10, ".depth.png")), big_depth));
  std::string error;
  const auto reader = SevenScenesReader::open(dir_.path().string(), &error);
  ASSERT_TRUE(reader.has_value()) << error;
  SevenScenesFrame frame;
  EXPECT_FALSE(reader->read(1, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file(frameName(7, ".color.png"))));
  EXPECT_TRUE(contains(error, "8x8"));
  EXPECT_FALSE(reader->read(2, &frame, &error));
  EXPECT_TRUE(contains(error, dir_.file(frameName(10, ".depth.png"))));
  EXPECT_TRUE(contains(error, "9x6"));
}

TEST_F(SevenScenesMalformedTest, RejectsIncompleteOrEmptyFolders) {
  fs::remove(dir_.file(frameName(7, ".pose.txt")));
  std::string error;
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, dir_.file(frameName(7, ".pose.txt"))));

  for (const int n : {3, 7, 10}) {
    for (const char* suffix : {".depth.png", ".color.png", ".pose.txt"}) {
      fs::remove(dir_.file(frameName(n, suffix)));
    }
  }
  EXPECT_FALSE(SevenScenesReader::open(dir_.path().string(), &error).has_value());
  EXPECT_TRUE(contains(error, "no frame"));

  EXPECT_FALSE(SevenScenesReader::open(dir_.file("does-not-exist"), &error).has_value());
  EXPECT_TRUE(contains(error, "does-not-exist"));
  EXPECT_FALSE(SevenScenesReader::open(dir_.file("does-not-exist"), nullptr).has_value());
}

}  // namespace
}  // namespace cblox
