#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/calibration/calibration_file.h"
#include "drivers/calibration/row_error.h"
#include "drivers/calibration/stereo_rectifier.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

// A raw rig: different intrinsics per camera, radtan distortion, the right camera 0.12 m to
// the right, 3 mm off in y and 2 mm in z, rotated 2 degrees about y and 1 degree about x.
StereoCameraCalibration rawRig() {
  StereoCameraCalibration rig;
  rig.source = "test rig";
  rig.left.intrinsics = {460.0, 458.0, 370.0, 245.0, 752, 480};
  rig.left.distortion = DistortionModel::kRadTan;
  rig.left.distortion_coefficients = {-0.28, 0.074, 0.0002, 0.00002};
  rig.right.intrinsics = {457.0, 456.0, 380.0, 250.0, 752, 480};
  rig.right.distortion = DistortionModel::kRadTan;
  rig.right.distortion_coefficients = {-0.27, 0.068, -0.0001, 0.00003};
  const Eigen::Matrix3d R_L_R =
      (Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(1.0 * M_PI / 180, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const Transformationd T_L_R(R_L_R, Eigen::Vector3d(0.12, 0.003, -0.002));
  rig.T_R_L = T_L_R.inverse();
  return rig;
}

cv::Mat toCv(const Eigen::Matrix3d& m) {
  cv::Mat out(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.at<double>(r, c) = m(r, c);
  }
  return out;
}

// Raw pixel of p_C through the camera's lens (OpenCV's model).
cv::Point2d rawPixel(const CameraCalibration& camera, const Eigen::Vector3d& p_C) {
  const PinholeIntrinsics& in = camera.intrinsics;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << in.fx, 0, in.cx, 0, in.fy, in.cy, 0, 0, 1);
  std::vector<cv::Point3d> points{{p_C.x(), p_C.y(), p_C.z()}};
  std::vector<cv::Point2d> pixels;
  cv::projectPoints(points, cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), K,
                    cv::Mat(camera.distortion_coefficients), pixels);
  return pixels[0];
}

// An 8-bit image of Gaussian blobs (sigma 1.5 px) centred at `centres`.
GrayImage blobs(int width, int height, const std::vector<cv::Point2d>& centres) {
  GrayImage image(width, height, 0);
  for (const cv::Point2d& c : centres) {
    for (int v = static_cast<int>(c.y) - 8; v <= static_cast<int>(c.y) + 8; ++v) {
      for (int u = static_cast<int>(c.x) - 8; u <= static_cast<int>(c.x) + 8; ++u) {
        if (!image.contains(u, v)) continue;
        const double d2 = (u - c.x) * (u - c.x) + (v - c.y) * (v - c.y);
        image(u, v) = static_cast<uint8_t>(
            std::max<double>(image(u, v), std::lround(250.0 * std::exp(-d2 / (2 * 1.5 * 1.5)))));
      }
    }
  }
  return image;
}

// Intensity centroid of the blob nearest `guess` (window +-6 px).
cv::Point2d centroid(const GrayImage& image, cv::Point2d guess) {
  double sum = 0, su = 0, sv = 0;
  for (int v = static_cast<int>(std::lround(guess.y)) - 6;
       v <= static_cast<int>(std::lround(guess.y)) + 6; ++v) {
    for (int u = static_cast<int>(std::lround(guess.x)) - 6;
         u <= static_cast<int>(std::lround(guess.x)) + 6; ++u) {
      if (!image.contains(u, v)) continue;
      const double w = image(u, v);
      sum += w;
      su += w * u;
      sv += w * v;
    }
  }
  return {su / sum, sv / sum};
}

// The whole chain on analytic points: blobs drawn at the raw (distorted) pixels of known 3D
// points land, after rectification, on the same row in both images, at the disparity
// fx * baseline / z of the rectified calibration.
TEST(StereoRectifierTest, PointsLandOnTheSameRowAtTheirDisparity) {
  const StereoCameraCalibration rig = rawRig();
  std::string error;
  const auto rectifier = StereoRectifier::create(rig, &error);
  ASSERT_NE(rectifier, nullptr) << error;
  EXPECT_FALSE(rectifier->passthrough());
  const RectifiedStereoCalibration& rect = rectifier->rectified();
  EXPECT_NEAR(rect.baseline_m, Eigen::Vector3d(0.12, 0.003, -0.002).norm(), 1e-9);

  // The rectified left camera L is the raw left camera C0 rotated by R_L_C0 = T_B_L^-1.
  const Eigen::Matrix3d R_C0_L = rect.T_B_L.rotationMatrix();  // no body frame: B = C0
  const Transformationd T_C1_C0 = rig.T_R_L;
  std::vector<Eigen::Vector3d> points_L;
  for (double x : {-0.8, -0.3, 0.3, 0.8}) {
    for (double y : {-0.5, 0.0, 0.5}) points_L.emplace_back(x, y, 3.0 + 0.3 * (x + y));
  }
  std::vector<cv::Point2d> raw_left, raw_right, expect_left;
  for (const Eigen::Vector3d& p_L : points_L) {
    const Eigen::Vector3d p_C0 = R_C0_L * p_L;
    raw_left.push_back(rawPixel(rig.left, p_C0));
    raw_right.push_back(rawPixel(rig.right, T_C1_C0 * p_C0));
    const PinholeIntrinsics& K = rect.intrinsics;
    expect_left.emplace_back(K.fx * p_L.x() / p_L.z() + K.cx, K.fy * p_L.y() / p_L.z() + K.cy);
  }
  GrayImage left, right;
  rectifier->rectify(blobs(752, 480, raw_left), blobs(752, 480, raw_right), &left, &right);
  ASSERT_EQ(left.width, 752);
  ASSERT_EQ(right.height, 480);
  for (size_t i = 0; i < points_L.size(); ++i) {
    const double disparity = rect.intrinsics.fx * rect.baseline_m / points_L[i].z();
    const cv::Point2d l = centroid(left, expect_left[i]);
    const cv::Point2d r = centroid(right, expect_left[i] - cv::Point2d(disparity, 0));
    EXPECT_NEAR(l.x, expect_left[i].x, 0.05) << i;
    EXPECT_NEAR(l.y, expect_left[i].y, 0.05) << i;
    EXPECT_NEAR(r.y, l.y, 0.08) << i;  // same row (8-bit blobs, fixed-point maps)
    EXPECT_NEAR(l.x - r.x, disparity, 0.05) << i;
  }
}

TEST(StereoRectifierTest, RectifiedPairPassesThroughUnchanged) {
  StereoCameraCalibration rig;
  rig.source = "sim";
  rig.left.intrinsics = rig.right.intrinsics = {458, 458, 375.5, 239.5, 64, 48};
  rig.T_R_L = Transformationd(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.11, 0, 0));
  std::string error;
  const auto rectifier = StereoRectifier::create(rig, &error);
  ASSERT_NE(rectifier, nullptr) << error;
  EXPECT_TRUE(rectifier->passthrough());
  EXPECT_EQ(rectifier->rectified().intrinsics.fx, 458.0);
  EXPECT_EQ(rectifier->rectified().baseline_m, 0.11);
  GrayImage a(64, 48), b(64, 48), l, r;
  for (size_t i = 0; i < a.data.size(); ++i) {
    a.data[i] = static_cast<uint8_t>(i * 7);
    b.data[i] = static_cast<uint8_t>(i * 3);
  }
  rectifier->rectify(a, b, &l, &r);
  EXPECT_EQ(l.data, a.data);
  EXPECT_EQ(r.data, b.data);
  // A wrong image size is refused with both sizes named.
  try {
    rectifier->rectify(GrayImage(32, 48), b, &l, &r);
    ADD_FAILURE() << "accepted a 32x48 image";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("32x48"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("64x48"), std::string::npos) << e.what();
  }
}

TEST(StereoRectifierTest, RefusesUnusableRigs) {
  std::string error;
  StereoCameraCalibration swapped = rawRig();
  swapped.T_R_L = swapped.T_R_L.inverse();  // right camera at -x
  EXPECT_EQ(StereoRectifier::create(swapped, &error), nullptr);
  EXPECT_NE(error.find("swapped"), std::string::npos) << error;
  StereoCameraCalibration vertical = rawRig();
  vertical.T_R_L = Transformationd(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, -0.1, 0));
  EXPECT_EQ(StereoRectifier::create(vertical, &error), nullptr);
  EXPECT_NE(error.find("vertically"), std::string::npos) << error;
  StereoCameraCalibration sizes = rawRig();
  sizes.right.intrinsics.width = 640;
  EXPECT_EQ(StereoRectifier::create(sizes, &error), nullptr);
  EXPECT_NE(error.find("640x480"), std::string::npos) << error;
  StereoCameraCalibration models = rawRig();
  models.right.distortion = DistortionModel::kEquidistant;
  EXPECT_EQ(StereoRectifier::create(models, &error), nullptr);
  EXPECT_NE(error.find("distortion models differ"), std::string::npos) << error;
  EXPECT_EQ(error.rfind("test rig: ", 0), 0u) << error;
  StereoCameraCalibration coefficients = rawRig();
  coefficients.right.distortion_coefficients.resize(3);
  EXPECT_EQ(StereoRectifier::create(coefficients, &error), nullptr);
  EXPECT_NE(error.find("right camera: radtan needs 4"), std::string::npos) << error;
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

const char* kCamchain = R"(
cam0:
  camera_model: pinhole
  intrinsics: [460.0, 458.0, 370.0, 245.0]
  distortion_model: radtan
  distortion_coeffs: [-0.28, 0.074, 0.0002, 0.00002]
  resolution: [752, 480]
  rostopic: /cam0/image_raw
cam1:
  camera_model: pinhole
  intrinsics: [457.0, 456.0, 380.0, 250.0]
  distortion_model: equidistant
  distortion_coeffs: [0.01, 0.002, 0.0, 0.0]
  resolution: [752, 480]
  T_cn_cnm1:
  - [1.0, 0.0, 0.0, -0.11]
  - [0.0, 1.0, 0.0, 0.001]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
  rostopic: /cam1/image_raw
)";

TEST(CalibrationFileTest, ReadsKalibrCamchain) {
  test::TempDir dir("cblox_calibration");
  const std::string path = (dir.path() / "camchain.yaml").string();
  writeText(path, kCamchain);
  const StereoCameraCalibration c = loadStereoCalibration(path, true);
  EXPECT_EQ(c.source, path);
  EXPECT_EQ(c.left.intrinsics.fx, 460.0);
  EXPECT_EQ(c.left.intrinsics.cy, 245.0);
  EXPECT_EQ(c.left.intrinsics.width, 752);
  EXPECT_EQ(c.left.distortion, DistortionModel::kRadTan);
  EXPECT_EQ(c.left.distortion_coefficients[1], 0.074);
  EXPECT_EQ(c.right.distortion, DistortionModel::kEquidistant);
  EXPECT_EQ(c.right.intrinsics.cx, 380.0);
  EXPECT_EQ(c.T_R_L.translation().x(), -0.11);
  EXPECT_EQ(c.T_R_L.translation().y(), 0.001);
  EXPECT_FALSE(c.left.T_B_C.has_value());
  EXPECT_EQ(c.right.distortion_key, path + ".cam1.distortion_coeffs");
  // Mono: cam1 is not read.
  const StereoCameraCalibration mono = loadStereoCalibration(path, false);
  EXPECT_EQ(mono.right.intrinsics.fx, 0.0);
}

// OpenCV's FileStorage, as its stereo_calib sample writes it: one file with everything, and
// the sample's own pair of files (intrinsics.yml + extrinsics.yml); YAML, XML and JSON.
TEST(CalibrationFileTest, ReadsOpenCvYamlAndXml) {
  test::TempDir dir("cblox_calibration");
  const cv::Mat M1 = (cv::Mat_<double>(3, 3) << 460, 0, 370, 0, 458, 245, 0, 0, 1);
  const cv::Mat M2 = (cv::Mat_<double>(3, 3) << 457, 0, 380, 0, 456, 250, 0, 0, 1);
  const cv::Mat D1 = (cv::Mat_<double>(1, 5) << -0.28, 0.074, 0.0002, 0.00002, 0.01);
  const cv::Mat D2 = (cv::Mat_<double>(1, 5) << -0.27, 0.068, -0.0001, 0.00003, 0.0);
  const Eigen::Matrix3d R_e = Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const cv::Mat R = toCv(R_e);
  const cv::Mat T = (cv::Mat_<double>(3, 1) << -0.12, 0.002, 0.001);
  for (const std::string ext : {".yml", ".xml", ".json"}) {
    const std::string one = (dir.path() / ("stereo" + ext)).string();
    {
      cv::FileStorage fs(one, cv::FileStorage::WRITE);
      fs << "image_width" << 752 << "image_height" << 480 << "M1" << M1 << "D1" << D1 << "M2"
         << M2 << "D2" << D2 << "R" << R << "T" << T;
    }
    const StereoCameraCalibration c = loadStereoCalibration(one, true);
    EXPECT_EQ(c.left.intrinsics.fx, 460.0) << ext;
    EXPECT_EQ(c.right.intrinsics.cy, 250.0) << ext;
    EXPECT_EQ(c.left.intrinsics.height, 480) << ext;
    ASSERT_EQ(c.left.distortion_coefficients.size(), 5u) << ext;
    EXPECT_EQ(c.left.distortion_coefficients[4], 0.01) << ext;
    EXPECT_EQ(c.left.distortion, DistortionModel::kRadTan) << ext;
    EXPECT_NEAR((c.T_R_L.rotationMatrix() - R_e).norm(), 0.0, 1e-12) << ext;
    EXPECT_EQ(c.T_R_L.translation().x(), -0.12) << ext;
  }
  // The sample's two files, imageSize given as [w, h].
  const std::string intrinsics = (dir.path() / "intrinsics.yml").string();
  {
    cv::FileStorage fs(intrinsics, cv::FileStorage::WRITE);
    fs << "imageSize" << std::vector<int>{640, 480} << "M1" << M1 << "D1" << D1 << "M2" << M2
       << "D2" << D2;
  }
  try {
    loadStereoCalibration(intrinsics, true);
    ADD_FAILURE() << "accepted intrinsics without extrinsics";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("extrinsics.yml"), std::string::npos) << e.what();
  }
  {
    cv::FileStorage fs((dir.path() / "extrinsics.yml").string(), cv::FileStorage::WRITE);
    fs << "R" << R << "T" << T;
  }
  const StereoCameraCalibration pair = loadStereoCalibration(intrinsics, true);
  EXPECT_EQ(pair.left.intrinsics.width, 640);
  EXPECT_EQ(pair.T_R_L.translation().z(), 0.001);
}

TEST(CalibrationFileTest, ErrorsNameFileAndKey) {
  test::TempDir dir("cblox_calibration");
  struct Case {
    std::string text;
    std::string message;
  };
  const std::string head = "%YAML:1.0\n---\nimage_width: 752\nimage_height: 480\n";
  const std::string m1 =
      "M1: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n  data: [460, 0, 370, 0, 458, 245, "
      "0, 0, 1]\n";
  const std::string m2 = "M2: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n  data: [457, 0, "
                         "380, 0, 456, 250, 0, 0, 1]\n";
  const std::string d4 = "D1: !!opencv-matrix\n  rows: 1\n  cols: 4\n  dt: d\n  data: [0.1, 0, "
                         "0, 0]\n";
  const std::string d3 = "D2: !!opencv-matrix\n  rows: 1\n  cols: 3\n  dt: d\n  data: [0.1, 0, "
                         "0]\n";
  const std::string r = "R: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n  data: [1, 0, 0, 0, "
                        "1, 0, 0, 0, 1]\n";
  const std::string t2 = "T: !!opencv-matrix\n  rows: 2\n  cols: 1\n  dt: d\n  data: [-0.1, 0]\n";
  const Case cases[] = {
      {head + d4, "M1"},
      {head + m1 + d4, "M2"},
      {head + m1 + d4 + m2 + d3, ".D2: radtan needs 4, 5, 8, 12 or 14"},
      {head + m1 + d4 + m2 + r + t2, ".T: expected 3 numbers"},
      {"%YAML:1.0\n---\n" + m1, "image_width"},
      {"cam0:\n  intrinsics: [1, 2]\n  resolution: [640, 480]\n", "cam0.intrinsics"},
      {"cam0:\n  intrinsics: [400, 400, 320, 240]\n  resolution: [640, 480]\n"
       "  distortion_model: omni\n",
       "cam0.distortion_model"},
      {"cam0: [1, 2\n", "camchain"},
      // B14: OpenCV 4.6's XML parser dereferenced a null pointer on an embedded NUL; B5: its
      // YAML parser threw std::length_error. Refused before OpenCV parses.
      {std::string("<?xml von=\0\0\0\"0R\"<!dt:\0atopag>\n", 31), "NUL byte at offset 10"},
      {"<?xml vsn=", "not well-formed XML (line 1"},  // B14 without a NUL
      {"%YAML:1.\n -  d\n0a--\nimag40296y2%pYte: i'", "not well-formed YAML"},  // B15: a hang
      {"<?xml version=\"1.0\"?>\n<opencv_storage>\n<image_width>752</image_width>\n",
       "not well-formed XML (line 4"},  // cut short: no closing tag
      {head + m1 + std::string("D1: [0\0]\n", 10),
       "NUL byte at offset " + std::to_string(head.size() + m1.size() + 6)},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string path = (dir.path() / ("case" + std::to_string(i++) + ".yaml")).string();
    writeText(path, c.text);
    try {
      loadStereoCalibration(path, true);
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const CalibrationError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path, 0), 0u) << what;
      if (c.message != "camchain") {
        EXPECT_NE(what.find(c.message), std::string::npos) << c.text << " -> " << what;
      }
    }
  }
  try {
    loadStereoCalibration((dir.path() / "absent.yaml").string(), true);
    ADD_FAILURE() << "accepted a missing file";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
}

TEST(RowErrorTest, SummaryAndChessboard) {
  const RowErrorStats s = summarizeRowErrors({0.3, 0.1, 0.2, 0.5, 0.4, 0.0, 0.6, 0.7, 0.8, 0.9});
  EXPECT_EQ(s.samples, 10u);
  EXPECT_EQ(s.median_px, 0.5);
  EXPECT_EQ(s.p90_px, 0.9);
  EXPECT_EQ(s.max_px, 0.9);
  EXPECT_EQ(summarizeRowErrors({}).samples, 0u);

  // A drawn board (7x5 inner corners, 30 px squares) and the same board 2 px lower.
  cv::Mat left(300, 400, CV_8UC1, cv::Scalar(255));
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 8; ++col) {
      if ((row + col) % 2 == 0) {
        cv::rectangle(left, cv::Rect(60 + 30 * col, 50 + 30 * row, 30, 30), cv::Scalar(0),
                      cv::FILLED);
      }
    }
  }
  cv::Mat right;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -20, 0, 1, 2);
  cv::warpAffine(left, right, shift, left.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                 cv::Scalar(255));
  std::vector<double> offsets;
  ASSERT_TRUE(chessboardRowOffsets(left, right, cv::Size(7, 5), &offsets));
  ASSERT_EQ(offsets.size(), 35u);
  for (double d : offsets) EXPECT_NEAR(d, 2.0, 0.05);
  // No board: nothing appended.
  EXPECT_FALSE(chessboardRowOffsets(cv::Mat(300, 400, CV_8UC1, cv::Scalar(128)), right,
                                    cv::Size(7, 5), &offsets));
  EXPECT_EQ(offsets.size(), 35u);
}

}  // namespace
}  // namespace cblox
