#include "drivers/dataset/kitti_odometry_reader.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "drivers/calibration/row_error.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

const std::string kKittiDir = std::string(CBLOX_SHARED_DATA_DIR) + "/kitti-odometry-51";

cv::Mat toMat(const GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.data.data()))
      .clone();
}

TEST(KittiOdometryReaderTest, ReadsTheSharedClip) {
  if (!fs::is_directory(kKittiDir)) {
    GTEST_SKIP() << "shared data not present at " << kKittiDir
                 << " (only available next to the project checkout)";
  }
  std::string error;
  const std::optional<KittiOdometryReader> reader = KittiOdometryReader::open(kKittiDir, &error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), 51u);
  // calib.txt's P0 and P1 (fx = fy = 707.0912, P1[0][3] = -379.8145).
  const RectifiedStereoCalibration& c = reader->calibration();
  EXPECT_EQ(c.intrinsics.fx, 707.0912);
  EXPECT_EQ(c.intrinsics.fy, 707.0912);
  EXPECT_EQ(c.intrinsics.cx, 601.8873);
  EXPECT_EQ(c.intrinsics.cy, 183.1104);
  EXPECT_EQ(c.intrinsics.width, 1226);
  EXPECT_EQ(c.intrinsics.height, 370);
  EXPECT_NEAR(c.baseline_m, 379.8145 / 707.0912, 1e-12);
  EXPECT_TRUE(c.T_B_L.translation().isZero());
  for (size_t i = 0; i < reader->size(); ++i) {
    EXPECT_EQ(reader->timestampNs(i), static_cast<int64_t>(i) * 100000000) << i;
  }
  EXPECT_NEAR(reader->rateHz(), 10.0, 1e-9);
  ASSERT_TRUE(reader->hasGroundTruth());
  EXPECT_EQ(reader->groundTruthPath(), fs::path(kKittiDir + "/poses.txt").lexically_normal());

  KittiStereoFrame frame;
  ASSERT_TRUE(reader->read(1, &frame, &error)) << error;
  EXPECT_EQ(frame.timestamp_ns, 100000000);
  ASSERT_TRUE(frame.T_G_L.has_value());
  // poses.txt's second row: (-0.01401751, -0.02820321, 1.198998), about identity rotation.
  EXPECT_NEAR(frame.T_G_L->translation().x(), -1.401751e-02, 1e-12);
  EXPECT_NEAR(frame.T_G_L->translation().y(), -2.820321e-02, 1e-12);
  EXPECT_NEAR(frame.T_G_L->translation().z(), 1.198998, 1e-12);
  EXPECT_NEAR(frame.T_G_L->rotationMatrix()(0, 1), 7.196824e-04, 1e-6);
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  EXPECT_TRUE(frame.T_G_L->translation().isZero(1e-9));
  EXPECT_EQ(frame.left.width, 1226);
  EXPECT_EQ(frame.right.height, 370);
  // The images are the files, unchanged (KITTI rectified them).
  const cv::Mat file = cv::imread(reader->leftImagePath(0), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::norm(toMat(frame.left), file, cv::NORM_INF), 0.0);
  // A rectified pair: features found again in the right image lie on the same row.
  std::vector<double> offsets;
  featureRowOffsets(toMat(frame.left), toMat(frame.right), 8, &offsets);
  ASSERT_GT(offsets.size(), 50u);
  EXPECT_LT(summarizeRowErrors(std::move(offsets)).median_px, 0.5);

  EXPECT_FALSE(reader->read(51, &frame, &error));
  EXPECT_NE(error.find("out of range"), std::string::npos) << error;
}

/// A three-pair sequence written from scratch, with the rows a test breaks.
class KittiSyntheticTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < 3; ++i) {
      writeImage("image_0/00000" + std::to_string(i) + ".png");
      writeImage("image_1/00000" + std::to_string(i) + ".png");
    }
    write("calib.txt",
          "P0: 500 0 20 0 0 500 15 0 0 0 1 0\n"
          "P1: 500 0 20 -250 0 500 15 0 0 0 1 0\n"
          "P2: 500 0 20 30 0 500 15 0.1 0 0 1 0.002\n"
          "P3: 500 0 20 -220 0 500 15 0.1 0 0 1 0.002\n"
          "Tr: 0 -1 0 0 0 0 -1 0 1 0 0 -0.3\n");
    write("times.txt", "0.0\n0.1\n0.2\n");
    write("poses.txt",
          "1 0 0 0 0 1 0 0 0 0 1 0\n"
          "1 0 0 0.1 0 1 0 0 0 0 1 1.0\n"
          "1 0 0 0.2 0 1 0 0 0 0 1 2.0\n");
  }
  std::string folder() const { return (dir_.path() / "seq").string(); }
  void write(const std::string& name, const std::string& text) const {
    const fs::path path = dir_.path() / "seq" / name;
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
  }
  void writeImage(const std::string& name, int type = CV_8UC1, int width = 40) const {
    const fs::path path = dir_.path() / "seq" / name;
    fs::create_directories(path.parent_path());
    cv::Mat image(30, width, type, cv::Scalar::all(90));
    ASSERT_TRUE(cv::imwrite(path.string(), image));
  }
  /// open() fails with a message holding `file` and `what`.
  void expectRefused(const std::string& file, const std::string& what) const {
    std::string error;
    EXPECT_FALSE(KittiOdometryReader::open(folder(), &error).has_value());
    EXPECT_NE(error.find(file), std::string::npos) << error;
    EXPECT_NE(error.find(what), std::string::npos) << error;
  }
  test::TempDir dir_{"kitti"};
};

TEST_F(KittiSyntheticTest, OpensAndSaysWhatItDoesNotUse) {
  std::string error;
  const auto reader = KittiOdometryReader::open(folder(), &error);
  ASSERT_TRUE(reader.has_value()) << error;
  EXPECT_EQ(reader->size(), 3u);
  EXPECT_EQ(reader->calibration().baseline_m, 0.5);
  EXPECT_EQ(reader->calibration().intrinsics.width, 40);
  EXPECT_EQ(reader->calibration().intrinsics.height, 30);
  ASSERT_FALSE(reader->notes().empty());
  EXPECT_NE(reader->notes()[0].find("P2, P3, Tr read and not used"), std::string::npos)
      << reader->notes()[0];
  KittiStereoFrame frame;
  ASSERT_TRUE(reader->read(2, &frame, &error)) << error;
  EXPECT_EQ(frame.timestamp_ns, 200000000);
  EXPECT_EQ(frame.T_G_L->translation(), Eigen::Vector3d(0.2, 0.0, 2.0));
  EXPECT_EQ(frame.left.data[0], 90);
}

TEST_F(KittiSyntheticTest, FindsTheGroundTruthInKittisDatasetLayout) {
  // dataset/sequences/seq and dataset/poses/seq.txt: the same poses, found two levels up.
  const fs::path root = dir_.path() / "dataset";
  fs::create_directories(root / "sequences");
  fs::create_directories(root / "poses");
  fs::rename(dir_.path() / "seq" / "poses.txt", root / "poses" / "seq.txt");
  fs::rename(dir_.path() / "seq", root / "sequences" / "seq");
  std::string error;
  const auto reader =
      KittiOdometryReader::open((root / "sequences" / "seq").string() + "/", &error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_TRUE(reader->hasGroundTruth());
  EXPECT_EQ(reader->groundTruthPath(), (root / "poses" / "seq.txt").string());
  // Without any pose file: no ground truth, and the notes say where it was looked for.
  fs::remove(root / "poses" / "seq.txt");
  const auto bare = KittiOdometryReader::open((root / "sequences" / "seq").string(), &error);
  ASSERT_TRUE(bare.has_value()) << error;
  EXPECT_FALSE(bare->hasGroundTruth());
  KittiStereoFrame frame;
  ASSERT_TRUE(bare->read(0, &frame, &error)) << error;
  EXPECT_FALSE(frame.T_G_L.has_value());
}

TEST_F(KittiSyntheticTest, RefusesMissingOrUnpairedImages) {
  fs::remove(dir_.path() / "seq/image_1/000001.png");
  expectRefused("image_1/000001.png", "missing (");
  writeImage("image_1/000001.png");
  writeImage("image_0/000003.png");  // a left image more than right ones
  expectRefused("image_1/000003.png", "has no partner");
  fs::remove(dir_.path() / "seq/image_0/000003.png");
  writeImage("image_0/12.png");
  expectRefused("image_0/12.png", "not named NNNNNN.png");
  fs::remove(dir_.path() / "seq/image_0/12.png");
  fs::remove_all(dir_.path() / "seq/image_1");
  expectRefused("image_1", "missing");
}

TEST_F(KittiSyntheticTest, RefusesBadTimes) {
  write("times.txt", "0.0\n0.1\n");
  expectRefused("times.txt", "2 times for 3 image pairs");
  write("times.txt", "0.0\n0.2\n0.1\n");
  expectRefused("times.txt:3", "times must increase");
  write("times.txt", "0.0\n0.1 0.2\n0.3\n");
  expectRefused("times.txt:2", "expected one time in seconds");
  write("times.txt", "0.0\nnan\n0.3\n");
  expectRefused("times.txt:2", "expected one time in seconds");
  fs::remove(dir_.path() / "seq/times.txt");
  expectRefused("times.txt", "missing");
}

TEST_F(KittiSyntheticTest, RefusesBadCalibration) {
  struct Case {
    const char* calib;
    const char* where;
    const char* what;
  };
  const Case cases[] = {
      {"500 0 20 0 0 500 15 0 0 0 1 0\n", "calib.txt:1", "expected 'LABEL: 12 numbers'"},
      {"P1: 500 0 20 -250 0 500 15 0 0 0 1 0\n", "calib.txt", "P0 is missing"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\n", "calib.txt", "P1 is missing"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\nP1: 500 0 20 -250 0 500 15 0 0 0 1\n", "calib.txt:2",
       "P1: expected 12 numbers, got 11"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\nP1: 500 0 20 -250 0 500 15 0 0 0 1 x\n", "calib.txt:2",
       "'x' is not a finite number"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\nP1: 510 0 20 -250 0 510 15 0 0 0 1 0\n", "calib.txt:2",
       "not a rectified pair"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\nP1: 500 0 20 -250 0 500 15 3 0 0 1 0\n", "calib.txt:2",
       "translation is not along x"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\nP1: 500 0 20 0 0 500 15 0 0 0 1 0\n", "calib.txt:2",
       "P1 has no baseline"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\nP1: 500 0 20 250 0 500 15 0 0 0 1 0\n", "calib.txt:2",
       "P1 has no baseline"},
      {"P0: 500 0 20 40 0 500 15 0 0 0 1 0\nP1: 500 0 20 -250 0 500 15 0 0 0 1 0\n", "calib.txt:1",
       "P0 has a translation"},
      {"P0: 500 2 20 0 0 500 15 0 0 0 1 0\nP1: 500 2 20 -250 0 500 15 0 0 0 1 0\n", "calib.txt:1",
       "P0 must be K [I | 0]"},
      {"P0: -500 0 20 0 0 500 15 0 0 0 1 0\nP1: -500 0 20 -250 0 500 15 0 0 0 1 0\n", "calib.txt:1",
       "fx and fy must be > 0"},
      {"P0: 500 0 90 0 0 500 15 0 0 0 1 0\nP1: 500 0 90 -250 0 500 15 0 0 0 1 0\n", "calib.txt:1",
       "principal point"},
      {"P0: 500 0 20 0 0 500 15 0 0 0 1 0\nP0: 500 0 20 0 0 500 15 0 0 0 1 0\n", "calib.txt:2",
       "P0 repeated"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.calib);
    write("calib.txt", c.calib);
    expectRefused(c.where, c.what);
  }
}

TEST_F(KittiSyntheticTest, RefusesBadPosesAndImages) {
  write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  expectRefused("poses.txt", "2 poses for 3 image pairs");
  write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  expectRefused("poses.txt:2", "not orthonormal");
  write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1\n");
  expectRefused("poses.txt:1", "expected 12 numbers, got 11");
  fs::remove(dir_.path() / "seq/poses.txt");
  writeImage("image_0/000000.png", CV_8UC3);
  expectRefused("image_0/000000.png", "8-bit single-channel");
  // A later image of another size is refused when it is read, naming it.
  writeImage("image_0/000000.png");
  writeImage("image_1/000002.png", CV_8UC1, 41);
  std::string error;
  const auto reader = KittiOdometryReader::open(folder(), &error);
  ASSERT_TRUE(reader.has_value()) << error;
  KittiStereoFrame frame;
  EXPECT_FALSE(reader->read(2, &frame, &error));
  EXPECT_NE(error.find("image_1/000002.png: size 41x30"), std::string::npos) << error;
}

}  // namespace
}  // namespace cblox
