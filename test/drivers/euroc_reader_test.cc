#include "drivers/dataset/euroc_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/calibration/row_error.h"
#include "test/test_support/contains.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

const std::string kEurocDir = std::string(CBLOX_SHARED_DATA_DIR) + "/euroc-v101-micro";

using test::contains;
using test::containsLine;

cv::Mat toMat(const GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.data.data()))
      .clone();
}

// Median |v_left - v_right| of corners of `left` found again in `right` (featureRowOffsets);
// *matches receives their number.
double medianRowOffset(const cv::Mat& left, const cv::Mat& right, int max_row_offset,
                       size_t* matches) {
  std::vector<double> offsets;
  featureRowOffsets(left, right, max_row_offset, &offsets);
  *matches = offsets.size();
  return offsets.empty() ? 1e9 : summarizeRowErrors(std::move(offsets)).median_px;
}

TEST(EurocReaderTest, ParsesRealData) {
  if (!fs::is_directory(kEurocDir)) {
    GTEST_SKIP() << "shared data not present at " << kEurocDir
                 << " (only available next to the project checkout)";
  }
  std::string error;
  const std::optional<EurocReader> reader = EurocReader::open(kEurocDir, {}, &error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), 40u);
  EXPECT_EQ(reader->folder(), kEurocDir + "/mav0");
  EXPECT_EQ(reader->timestampNs(0), 1403715273262142976);
  EXPECT_EQ(reader->timestampNs(39), 1403715275212143104);
  for (size_t i = 1; i < reader->size(); ++i) {
    const int64_t step = reader->timestampNs(i) - reader->timestampNs(i - 1);
    EXPECT_NEAR(static_cast<double>(step), 50e6, 1e3) << i;  // 20 Hz
  }
  EXPECT_DOUBLE_EQ(reader->rateHz(), 20.0);
  EXPECT_TRUE(reader->skipped().empty());
  EXPECT_FALSE(reader->hasGroundTruth());
  EXPECT_TRUE(
      containsLine(reader->notes(), "no ground truth: mav0/state_groundtruth_estimate0/data.csv"));

  // Raw calibration as in sensor.yaml.
  const EurocCameraCalibration& cam0 = reader->leftCamera();
  const EurocCameraCalibration& cam1 = reader->rightCamera();
  EXPECT_EQ(cam0.intrinsics.width, 752);
  EXPECT_EQ(cam0.intrinsics.height, 480);
  EXPECT_DOUBLE_EQ(cam0.intrinsics.fx, 458.654);
  EXPECT_DOUBLE_EQ(cam1.intrinsics.cx, 379.999);
  EXPECT_EQ(cam0.distortion_model, "radial-tangential");
  ASSERT_EQ(cam1.distortion_coefficients.size(), 4u);
  EXPECT_DOUBLE_EQ(cam1.distortion_coefficients[3], -3.55590700e-05);
  EXPECT_NEAR(cam0.T_B_S.translation().y(), -0.064676986768, 1e-9);

  // Rectified calibration: EuRoC's stereo baseline is 0.110 m; alpha = 0 zooms in a little.
  const RectifiedStereoCalibration& calibration = reader->calibration();
  EXPECT_EQ(calibration.intrinsics.width, 752);
  EXPECT_EQ(calibration.intrinsics.height, 480);
  EXPECT_NEAR(calibration.baseline_m, 0.110, 0.002);
  EXPECT_GT(calibration.intrinsics.fx, 400.0);
  EXPECT_LT(calibration.intrinsics.fx, 520.0);
  EXPECT_DOUBLE_EQ(calibration.intrinsics.fx, calibration.intrinsics.fy);
  EXPECT_NEAR(calibration.intrinsics.cx, 376.0, 60.0);
  EXPECT_NEAR(calibration.intrinsics.cy, 240.0, 40.0);
  RecordProperty("rectified_fx", std::to_string(calibration.intrinsics.fx));
  RecordProperty("rectified_cx", std::to_string(calibration.intrinsics.cx));
  RecordProperty("rectified_cy", std::to_string(calibration.intrinsics.cy));
  RecordProperty("baseline_m", std::to_string(calibration.baseline_m));
  // The rectified left camera sits at cam0's centre, the right one at cam1's centre.
  EXPECT_LT((calibration.T_B_L.translation() - cam0.T_B_S.translation()).norm(), 1e-12);
  const Eigen::Vector3d right_centre =
      calibration.T_B_L * Eigen::Vector3d(calibration.baseline_m, 0.0, 0.0);
  EXPECT_LT((right_centre - cam1.T_B_S.translation()).norm(), 1e-9);
  // Rectification only rotates the camera slightly (both cameras look the same way).
  const double angle =
      cam0.T_B_S.rotation().angularDistance(calibration.T_B_L.rotation()) * 180.0 / M_PI;
  EXPECT_LT(angle, 3.0);

  EurocStereoFrame frame;
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  EXPECT_EQ(frame.timestamp_ns, 1403715273262142976);
  EXPECT_EQ(frame.left.width, 752);
  EXPECT_EQ(frame.left.height, 480);
  EXPECT_EQ(frame.right.width, 752);
  EXPECT_EQ(frame.right.height, 480);
  EXPECT_FALSE(frame.T_G_L.has_value());
  ASSERT_TRUE(reader->read(39, &frame, &error)) << error;
  EXPECT_EQ(frame.timestamp_ns, 1403715275212143104);
  EXPECT_FALSE(reader->read(40, &frame, &error));
  EXPECT_TRUE(contains(error, "out of range"));

  // mav0/ itself opens the same sequence.
  const std::optional<EurocReader> same = EurocReader::open(kEurocDir + "/mav0", {}, &error);
  ASSERT_TRUE(same.has_value()) << error;
  EXPECT_EQ(same->size(), 40u);
  EXPECT_EQ(same->calibration().baseline_m, calibration.baseline_m);
}

TEST(EurocReaderTest, RectifiedRowsAlignOnRealImages) {
  if (!fs::is_directory(kEurocDir)) {
    GTEST_SKIP() << "shared data not present at " << kEurocDir
                 << " (only available next to the project checkout)";
  }
  std::string error;
  const std::optional<EurocReader> reader = EurocReader::open(kEurocDir, {}, &error);
  ASSERT_TRUE(reader.has_value()) << error;
  EurocStereoFrame frame;
  ASSERT_TRUE(reader->read(20, &frame, &error)) << error;

  size_t rectified_matches = 0;
  const double rectified =
      medianRowOffset(toMat(frame.left), toMat(frame.right), 10, &rectified_matches);
  size_t raw_matches = 0;
  const double raw = medianRowOffset(cv::imread(reader->leftImagePath(20), cv::IMREAD_UNCHANGED),
                                     cv::imread(reader->rightImagePath(20), cv::IMREAD_UNCHANGED),
                                     25, &raw_matches);
  RecordProperty("rectified_median_abs_dv", std::to_string(rectified));
  RecordProperty("rectified_matches", std::to_string(rectified_matches));
  RecordProperty("raw_median_abs_dv", std::to_string(raw));
  RecordProperty("raw_matches", std::to_string(raw_matches));
  EXPECT_GE(rectified_matches, 50u);
  EXPECT_LT(rectified, 0.5) << rectified_matches << " matches";
  EXPECT_GE(raw_matches, 20u);
  EXPECT_GT(raw, rectified + 0.5) << raw_matches << " raw matches";
}

// EuRoC V1_01's calibration, as in its sensor.yaml files.
constexpr const char* kCam0TBS =
    "[0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,\n"
    "         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,\n"
    "        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,\n"
    "         0.0, 0.0, 0.0, 1.0]";
constexpr const char* kCam1TBS =
    "[0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,\n"
    "         0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,\n"
    "        -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038,\n"
    "         0.0, 0.0, 0.0, 1.0]";
constexpr const char* kCam0Intrinsics = "[458.654, 457.296, 367.215, 248.375]";
constexpr const char* kCam1Intrinsics = "[457.587, 456.134, 379.999, 255.238]";
constexpr const char* kCam0RadTan = "[-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]";
constexpr const char* kCam1RadTan = "[-0.28368365,  0.07451284, -0.00010473, -3.55590700e-05]";

struct SensorFields {
  std::string T_BS_data;
  std::string intrinsics;
  std::string distortion_coefficients;
  std::string distortion_model = "radial-tangential";
  std::string camera_model = "pinhole";
  std::string resolution = "[752, 480]";
  std::string rate_hz = "rate_hz: 20\n";
};

// Same layout as EuRoC's files: T_BS.data starts on line 10 and, with the 4-line T_BS data
// above, camera_model is on line 18, intrinsics 19, distortion_model 20, coefficients 21.
std::string sensorYaml(const SensorFields& f) {
  return "%YAML:1.0\n"
         "# General sensor definitions.\n"
         "sensor_type: camera\n"
         "comment: VI-Sensor (MT9M034)\n"
         "\n"
         "# Sensor extrinsics wrt. the body-frame.\n"
         "T_BS:\n"
         "  cols: 4\n"
         "  rows: 4\n"
         "  data: " +
         f.T_BS_data +
         "\n\n"
         "# Camera specific definitions.\n" +
         f.rate_hz + "resolution: " + f.resolution + "\ncamera_model: " + f.camera_model +
         "\nintrinsics: " + f.intrinsics +
         " #fu, fv, cu, cv\ndistortion_model: " + f.distortion_model +
         "\ndistortion_coefficients: " + f.distortion_coefficients + "\n";
}

SensorFields cam0Fields() { return {kCam0TBS, kCam0Intrinsics, kCam0RadTan}; }
SensorFields cam1Fields() { return {kCam1TBS, kCam1Intrinsics, kCam1RadTan}; }

// Writes a small EuRoC folder (3 white 752x480 pairs, EuRoC's calibration) into a fresh
// temporary directory.
class EurocSyntheticTest : public testing::Test {
 protected:
  void SetUp() override {
    for (const char* camera : {"cam0", "cam1"}) fs::create_directories(mav0_ / camera / "data");
    writeSensor("cam0", cam0Fields());
    writeSensor("cam1", cam1Fields());
    const cv::Mat white(kHeight, kWidth, CV_8UC1, cv::Scalar(255));
    for (const char* camera : {"cam0", "cam1"}) {
      std::string csv = "#timestamp [ns],filename\n";
      for (const int64_t t : kTimestamps) {
        csv += std::to_string(t) + "," + std::to_string(t) + ".png\n";
        ASSERT_TRUE(cv::imwrite(image(camera, t), white));
      }
      writeText(std::string(camera) + "/data.csv", csv);
    }
  }
  // Path of a file under mav0/.
  std::string path(const std::string& relative) const { return (mav0_ / relative).string(); }
  std::string image(const std::string& camera, int64_t t) const {
    return path(camera + "/data/" + std::to_string(t) + ".png");
  }
  void writeText(const std::string& relative, const std::string& text) const {
    root_.write("mav0/" + relative, text);
  }
  void writeSensor(const std::string& camera, const SensorFields& fields) const {
    writeText(camera + "/sensor.yaml", sensorYaml(fields));
  }
  std::optional<EurocReader> open(std::string* error,
                                  const EurocReader::Options& options = {}) const {
    return EurocReader::open(root_.path().string(), options, error);
  }
  // Expects open() to fail with a message containing every needle.
  void expectOpenFails(const std::vector<std::string>& needles) const {
    std::string error;
    EXPECT_FALSE(open(&error).has_value());
    for (const std::string& needle : needles) EXPECT_TRUE(contains(error, needle));
  }

  static constexpr int kWidth = 752;
  static constexpr int kHeight = 480;
  static constexpr int64_t kTimestamps[3] = {1000000000, 1050000000, 1100000000};
  test::TempDir root_{"cblox_euroc"};
  fs::path mav0_ = root_.path() / "mav0";
};

TEST_F(EurocSyntheticTest, ValidFolderRectifiesWithoutBlackBorders) {
  std::string error;
  const std::optional<EurocReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), 3u);
  EXPECT_TRUE(reader->skipped().empty());
  EXPECT_EQ(reader->timestampNs(1), kTimestamps[1]);
  EXPECT_EQ(reader->leftImagePath(2), image("cam0", kTimestamps[2]));
  EXPECT_NEAR(reader->calibration().baseline_m, 0.110, 0.002);

  // alpha = 0: every rectified pixel comes from inside the raw image (no black border). Raw
  // images are white with a black 1-pixel frame: only the outermost rectified pixels may
  // come near that frame, everything 3 pixels in must stay white.
  cv::Mat framed(kHeight, kWidth, CV_8UC1, cv::Scalar(0));
  framed(cv::Rect(1, 1, kWidth - 2, kHeight - 2)).setTo(255);
  ASSERT_TRUE(cv::imwrite(image("cam0", kTimestamps[1]), framed));
  ASSERT_TRUE(cv::imwrite(image("cam1", kTimestamps[1]), framed));
  EurocStereoFrame frame;
  ASSERT_TRUE(reader->read(1, &frame, &error)) << error;
  EXPECT_EQ(frame.timestamp_ns, kTimestamps[1]);
  for (const GrayImage* image : {&frame.left, &frame.right}) {
    ASSERT_EQ(image->width, kWidth);
    ASSERT_EQ(image->height, kHeight);
    int darkest = 255;
    for (int v = 3; v < kHeight - 3; ++v) {
      for (int u = 3; u < kWidth - 3; ++u) darkest = std::min<int>(darkest, (*image)(u, v));
    }
    EXPECT_EQ(darkest, 255);
  }
  // Plain white raw images give plain white rectified images.
  ASSERT_TRUE(reader->read(2, &frame, &error)) << error;
  EXPECT_EQ(*std::min_element(frame.left.data.begin(), frame.left.data.end()), 255);
  EXPECT_EQ(*std::min_element(frame.right.data.begin(), frame.right.data.end()), 255);

  // mav0/ itself works too.
  const auto direct = EurocReader::open(mav0_.string(), {}, &error);
  ASSERT_TRUE(direct.has_value()) << error;
  EXPECT_EQ(direct->size(), 3u);
}

TEST_F(EurocSyntheticTest, EquidistantModelUsesFisheyeRectification) {
  for (SensorFields fields : {cam0Fields(), cam1Fields()}) {
    fields.distortion_model = "equidistant";
    fields.distortion_coefficients = "[0.01, -0.002, 0.0005, -0.0001]";
    writeSensor(fields.T_BS_data == kCam0TBS ? "cam0" : "cam1", fields);
  }
  std::string error;
  const std::optional<EurocReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  EXPECT_EQ(reader->leftCamera().distortion_model, "equidistant");
  EXPECT_NEAR(reader->calibration().baseline_m, 0.110, 0.002);
  EXPECT_GT(reader->calibration().intrinsics.fx, 300.0);
  EurocStereoFrame frame;
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  EXPECT_EQ(frame.left.width, kWidth);

  // Mixed models are rejected.
  writeSensor("cam1", cam1Fields());
  expectOpenFails({path("cam1/sensor.yaml"), "differs from cam0's 'equidistant'"});
}

TEST_F(EurocSyntheticTest, RejectsMissingOrBadSensorYaml) {
  fs::remove(path("cam1/sensor.yaml"));
  expectOpenFails({path("cam1/sensor.yaml"), "missing"});

  SensorFields fields = cam1Fields();
  fields.T_BS_data = "[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0]";
  writeSensor("cam1", fields);
  expectOpenFails({path("cam1/sensor.yaml") + ":10:", "T_BS.data", "expected 16 numbers, got 15"});

  fields.T_BS_data = "[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, zero, 1]";
  writeSensor("cam1", fields);
  expectOpenFails({path("cam1/sensor.yaml") + ":10:", "'zero' is not a finite number"});

  fields.T_BS_data = "[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1]";
  writeSensor("cam1", fields);
  expectOpenFails({path("cam1/sensor.yaml"), "reflection"});

  fields.T_BS_data = "[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1]";
  writeSensor("cam1", fields);
  expectOpenFails({path("cam1/sensor.yaml"), "last row must be 0 0 0 1"});
  writeSensor("cam1", cam1Fields());

  fields = cam0Fields();
  fields.camera_model = "omni";
  writeSensor("cam0", fields);
  expectOpenFails({path("cam0/sensor.yaml") + ":18:", "camera_model must be 'pinhole'", "omni"});

  fields = cam0Fields();
  fields.distortion_model = "fov";
  writeSensor("cam0", fields);
  expectOpenFails({path("cam0/sensor.yaml") + ":20:", "'fov' is not supported"});

  fields = cam0Fields();
  fields.distortion_coefficients = "[0.1, 0.2, 0.3]";
  writeSensor("cam0", fields);
  expectOpenFails({path("cam0/sensor.yaml") + ":21:", "radial-tangential needs 4"});

  fields = cam0Fields();
  fields.intrinsics = "[-458.654, 457.296, 367.215, 248.375]";
  writeSensor("cam0", fields);
  expectOpenFails({path("cam0/sensor.yaml") + ":19:", "fx must be > 0"});

  fields = cam0Fields();
  fields.rate_hz = "";
  writeSensor("cam0", fields);
  expectOpenFails({path("cam0/sensor.yaml"), "field 'rate_hz' is missing"});

  fields = cam0Fields();
  fields.resolution = "[640, 480]";
  writeSensor("cam0", fields);
  expectOpenFails({path("cam1/sensor.yaml"), "752x480 differs from cam0's 640x480"});

  fields = cam0Fields();
  fields.T_BS_data = "[1, 0, 0, 0,";  // unterminated flow sequence
  writeSensor("cam0", fields);
  expectOpenFails({path("cam0/sensor.yaml"), "YAML parse error"});

  // Swapping the cameras puts "cam1" at -x of "cam0".
  writeSensor("cam0", cam1Fields());
  writeSensor("cam1", cam0Fields());
  expectOpenFails({path("cam1/sensor.yaml"), "to the right (+x) of the left one"});
}

TEST_F(EurocSyntheticTest, RejectsMalformedCsv) {
  writeText("cam0/data.csv",
            "#timestamp [ns],filename\n1000000000,1000000000.png\n1050000000;1050000000.png\n");
  expectOpenFails({path("cam0/data.csv") + ":3:", "expected 'timestamp [ns],filename'"});

  writeText("cam0/data.csv", "#timestamp [ns],filename\n10.5,1000000000.png\n");
  expectOpenFails({path("cam0/data.csv") + ":2:", "'10.5' is not a non-negative integer"});

  writeText("cam0/data.csv", "#timestamp [ns],filename\n1000000000,1000000000.png\n");
  writeText("cam1/data.csv",
            "#timestamp [ns],filename\r\n1050000000,1050000000.png\r\n"
            "1000000000,1000000000.png\r\n");
  expectOpenFails({path("cam1/data.csv") + ":3:", "does not increase"});

  fs::remove(path("cam1/data.csv"));
  expectOpenFails({path("cam1/data.csv"), "missing"});
}

TEST_F(EurocSyntheticTest, SkipsMissingAndUnpairedImages) {
  fs::remove(image("cam1", kTimestamps[1]));
  // An extra cam0 entry without a cam1 partner.
  writeText("cam0/data.csv",
            "#timestamp [ns],filename\n1000000000,1000000000.png\n1050000000,1050000000.png\n"
            "1075000000,1075000000.png\n1100000000,1100000000.png\n");
  std::string error;
  const std::optional<EurocReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_EQ(reader->size(), 2u);
  EXPECT_EQ(reader->timestampNs(0), kTimestamps[0]);
  EXPECT_EQ(reader->timestampNs(1), kTimestamps[2]);
  ASSERT_EQ(reader->skipped().size(), 2u);
  EXPECT_TRUE(containsLine(reader->skipped(),
                           "cam1/data/1050000000.png: missing, frame 1050000000 skipped"));
  EXPECT_TRUE(containsLine(reader->skipped(),
                           "cam0/data/1075000000.png: no cam1 image with timestamp 1075000000"));
  EXPECT_TRUE(containsLine(reader->notes(), "2 image entries skipped"));

  // Nothing left at all.
  for (const int64_t t : kTimestamps) fs::remove(image("cam0", t));
  expectOpenFails({"no complete stereo pair"});
}

TEST_F(EurocSyntheticTest, RejectsWrongImages) {
  ASSERT_TRUE(
      cv::imwrite(image("cam0", kTimestamps[1]), cv::Mat(50, 100, CV_8UC1, cv::Scalar(255))));
  ASSERT_TRUE(cv::imwrite(image("cam1", kTimestamps[2]),
                          cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255))));
  std::string error;
  const std::optional<EurocReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  EurocStereoFrame frame;
  frame.timestamp_ns = -7;
  EXPECT_FALSE(reader->read(1, &frame, &error));
  EXPECT_TRUE(contains(error, image("cam0", kTimestamps[1])));
  EXPECT_TRUE(contains(error, "size 100x50 does not match sensor.yaml's resolution 752x480"));
  EXPECT_EQ(frame.timestamp_ns, -7);  // untouched
  EXPECT_FALSE(reader->read(2, &frame, &error));
  EXPECT_TRUE(contains(error, image("cam1", kTimestamps[2])));
  EXPECT_TRUE(contains(error, "8-bit single-channel"));
  // Deleted after open().
  fs::remove(image("cam1", kTimestamps[0]));
  EXPECT_FALSE(reader->read(0, &frame, &error));
  EXPECT_TRUE(contains(error, image("cam1", kTimestamps[0])));
  EXPECT_TRUE(contains(error, "missing"));
}

TEST_F(EurocSyntheticTest, InterpolatesGroundTruth) {
  // Body poses at 0.99 s (identity) and 1.04 s (0.1 rad about z, 0.5 m along x), then a 0.1 s
  // gap to 1.14 s: frame 0 (1.00 s) interpolates, frames 1 and 2 fall into the gap.
  const double half = 0.05;
  const std::string rest = ",0,0,0,0,0,0,0,0,0\n";
  writeText("state_groundtruth_estimate0/data.csv",
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
            "q_RS_y [], q_RS_z [], v..., b_w..., b_a...\n"
            "990000000,0,0,0,1,0,0,0" +
                rest + "1040000000,0.5,0,0," + std::to_string(std::cos(half)) + ",0,0," +
                std::to_string(std::sin(half)) + rest + "1140000000,0.5,0,0,1,0,0,0" + rest);
  std::string error;
  std::optional<EurocReader> reader = open(&error);
  ASSERT_TRUE(reader.has_value()) << error;
  EXPECT_TRUE(reader->hasGroundTruth());
  EXPECT_TRUE(containsLine(reader->notes(), "2 of 3 frames have no ground truth"));
  EurocStereoFrame frame;
  ASSERT_TRUE(reader->read(0, &frame, &error)) << error;
  ASSERT_TRUE(frame.T_G_L.has_value());
  const Transformationd A;
  const Transformationd B(Eigen::Quaterniond(std::cos(half), 0, 0, std::sin(half)),
                          Eigen::Vector3d(0.5, 0, 0));
  const Transformationd expected =
      Transformationd::interpolate(A, B, 0.2) * reader->calibration().T_B_L;
  EXPECT_TRUE(frame.T_G_L->isApprox(expected, 1e-6)) << *frame.T_G_L << " vs " << expected;
  ASSERT_TRUE(reader->read(1, &frame, &error)) << error;
  EXPECT_FALSE(frame.T_G_L.has_value());

  // A larger allowed gap gives every frame a pose.
  EurocReader::Options options;
  options.groundtruth_max_gap_s = 0.2;
  reader = open(&error, options);
  ASSERT_TRUE(reader.has_value()) << error;
  ASSERT_TRUE(reader->read(2, &frame, &error)) << error;
  ASSERT_TRUE(frame.T_G_L.has_value());
  EXPECT_FALSE(containsLine(reader->notes(), "have no ground truth"));

  // Malformed ground truth is an error naming file and line.
  writeText("state_groundtruth_estimate0/data.csv",
            "#timestamp, ...\n990000000,0,0,0,1,0,0,0\n1040000000,0.5,0,0,1\n");
  expectOpenFails({path("state_groundtruth_estimate0/data.csv") + ":3:", "at least 8"});
  writeText("state_groundtruth_estimate0/data.csv",
            "990000000,0,0,0,1,0,0,0\n990000000,0,0,0,1,0,0,0\n");
  expectOpenFails({path("state_groundtruth_estimate0/data.csv") + ":2:", "does not increase"});
  writeText("state_groundtruth_estimate0/data.csv", "990000000,0,0,0,2,0,0,0\n");
  expectOpenFails({path("state_groundtruth_estimate0/data.csv") + ":1:", "quaternion norm"});
}

TEST_F(EurocSyntheticTest, RejectsBadFoldersAndOptions) {
  std::string error;
  EXPECT_FALSE(EurocReader::open(root_.file("nope"), {}, &error).has_value());
  EXPECT_TRUE(contains(error, "nope"));
  EXPECT_FALSE(EurocReader::open((mav0_ / "cam0").string(), {}, &error).has_value());
  EXPECT_TRUE(contains(error, "not a EuRoC folder"));
  EurocReader::Options options;
  options.groundtruth_max_gap_s = 0.0;
  EXPECT_FALSE(open(&error, options).has_value());
  EXPECT_TRUE(contains(error, "groundtruth_max_gap_s"));
  EXPECT_FALSE(open(nullptr, options).has_value());
}

}  // namespace
}  // namespace cblox
