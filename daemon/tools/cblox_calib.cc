// cblox-calib: stereo calibration helper.
//
//   cblox-calib check --calibration rig.yaml --list stereo_calib.xml [--pattern 9x6]
//   cblox-calib check --calibration rig.yaml --pair left.png right.png [--pair ...]
//   cblox-calib check --euroc DIR [--frames N]
//   cblox-calib calibrate --list stereo_calib.xml --pattern 9x6 --square 0.025 --out rig.yml
//
// check: rectifies each pair with the calibration (drivers/calibration: Kalibr camchain or
// OpenCV YAML/XML; for --euroc the folder's own sensor.yaml files) and prints the rectified
// row error |v_left - v_right| of the same points: the inner corners of a chessboard where one
// is found in both images, else corners matched along the rows (scenes without a board).
// Exit status 0 when the median is at most --max-row-error px, 1 when above (the calibration
// does not fit these images), 2 for usage or input errors.
//
// calibrate: cv::calibrateCamera on each camera, then cv::stereoCalibrate starting from
// them, on the pairs where the board is found in both images; writes OpenCV YAML (M1 D1 M2
// D2 R T, image size, RMS) that check and cblox-capture's `calibration:` read.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/geometry/opencv_view.h"
#include "daemon/common/cli.h"
#include "drivers/calibration/calibration_file.h"
#include "drivers/calibration/opencv_storage.h"
#include "drivers/calibration/row_error.h"
#include "drivers/calibration/stereo_rectifier.h"
#include "drivers/dataset/euroc_reader.h"

namespace cblox {
namespace {

struct ImagePair {
  std::string left, right;
};

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// OpenCV's image list (the stereo_calib sample's stereo_calib.xml): left and right names
// alternate; relative names are relative to the list's folder.
std::vector<ImagePair> readImageList(const std::string& path) {
  std::string error;
  const std::optional<YAML::Node> root = readOpenCvStorage(path, &error);
  if (!root) throw InputError(error + " (expected an OpenCV image list)");
  if (root->size() == 0) throw InputError(path + ": not an OpenCV image list");
  const YAML::Node list = root->begin()->second;
  if (!list.IsSequence()) throw InputError(path + ": not an OpenCV image list");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::vector<std::string> names;
  for (const YAML::Node& node : list) {
    if (!node.IsScalar() || node.Scalar().empty()) {
      throw InputError(path + ": image " + std::to_string(names.size()) + " is not a file name");
    }
    const std::filesystem::path name = node.Scalar();
    names.push_back(name.is_absolute() ? name.string() : (folder / name).string());
  }
  if (names.size() % 2 != 0 || names.empty()) {
    throw InputError(path + ": expected left/right image names in pairs, got " +
                     std::to_string(names.size()) + " names");
  }
  std::vector<ImagePair> pairs;
  for (size_t i = 0; i < names.size(); i += 2) pairs.push_back({names[i], names[i + 1]});
  return pairs;
}

cv::Mat readGrey(const std::string& path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw InputError(path + ": cannot read image");
  return image;
}

cv::Size parsePattern(const std::string& text) {
  int cols = 0, rows = 0;
  char x = 0;
  if (std::sscanf(text.c_str(), "%d%c%d", &cols, &x, &rows) != 3 || x != 'x' || cols < 2 ||
      rows < 2) {
    throw InputError("--pattern must be COLSxROWS of inner corners (e.g. 9x6), got '" + text +
                     "'");
  }
  return {cols, rows};
}

void printStats(const char* what, const RowErrorStats& s) {
  std::printf("%s: %zu points, row error median %.3f px, p90 %.3f px, max %.3f px\n", what,
              s.samples, s.median_px, s.p90_px, s.max_px);
}

GrayImage toImage(const cv::Mat& mat) {
  GrayImage image(mat.cols, mat.rows);
  for (int v = 0; v < mat.rows; ++v) {
    std::copy(mat.ptr<uint8_t>(v), mat.ptr<uint8_t>(v) + mat.cols,
              image.data.begin() + static_cast<std::ptrdiff_t>(v) * mat.cols);
  }
  return image;
}

cv::Mat toMat(const GrayImage& image) { return cvView(image).clone(); }

// Row offsets of one rectified pair: the board's corners if found, else matched corners.
void pairOffsets(const cv::Mat& left, const cv::Mat& right, cv::Size pattern,
                 const std::string& name, std::vector<double>* all) {
  std::vector<double> offsets;
  const bool board = chessboardRowOffsets(left, right, pattern, &offsets);
  if (!board) featureRowOffsets(left, right, 10, &offsets);
  const RowErrorStats s = summarizeRowErrors(offsets);
  std::printf("  %s: %s, %zu points, median %.3f px, max %.3f px\n", name.c_str(),
              board ? "chessboard" : "matched corners", s.samples, s.median_px, s.max_px);
  all->insert(all->end(), offsets.begin(), offsets.end());
}

int check(const std::string& calibration_path, const std::vector<ImagePair>& pairs,
          const std::string& euroc, int frames, cv::Size pattern, double max_row_error) {
  std::vector<double> rectified, raw;
  if (!euroc.empty()) {
    std::string error;
    const auto reader = EurocReader::open(euroc, EurocReader::Options{}, &error);
    if (!reader) throw InputError(error);
    const RectifiedStereoCalibration& c = reader->calibration();
    std::printf("euroc %s: %zu pairs, rectified fx %.2f, baseline %.4f m\n", euroc.c_str(),
                reader->size(), c.intrinsics.fx, c.baseline_m);
    const size_t n = std::min(reader->size(), static_cast<size_t>(frames));
    for (size_t k = 0; k < n; ++k) {
      const size_t i = n > 1 ? k * (reader->size() - 1) / (n - 1) : 0;
      EurocStereoFrame frame;
      if (!reader->read(i, &frame, &error)) throw InputError(error);
      pairOffsets(toMat(frame.left), toMat(frame.right), pattern,
                  "pair " + std::to_string(i), &rectified);
      featureRowOffsets(readGrey(reader->leftImagePath(i)), readGrey(reader->rightImagePath(i)),
                        25, &raw);
    }
  } else {
    StereoCameraCalibration file;
    try {
      file = loadStereoCalibration(calibration_path, true);
    } catch (const CalibrationError& e) {
      throw InputError(e.what());
    }
    std::string error;
    const auto rectifier = StereoRectifier::create(file, &error);
    if (rectifier == nullptr) throw InputError(error);
    const RectifiedStereoCalibration& c = rectifier->rectified();
    std::printf("%s: rectified %dx%d fx %.2f fy %.2f cx %.2f cy %.2f, baseline %.4f\n",
                calibration_path.c_str(), c.intrinsics.width, c.intrinsics.height,
                c.intrinsics.fx, c.intrinsics.fy, c.intrinsics.cx, c.intrinsics.cy,
                c.baseline_m);
    for (const ImagePair& pair : pairs) {
      const cv::Mat left = readGrey(pair.left), right = readGrey(pair.right);
      GrayImage l, r;
      try {
        rectifier->rectify(toImage(left), toImage(right), &l, &r);
      } catch (const std::invalid_argument& e) {
        throw InputError(pair.left + ": " + e.what());
      }
      pairOffsets(toMat(l), toMat(r), pattern,
                  std::filesystem::path(pair.left).filename().string() + " / " +
                      std::filesystem::path(pair.right).filename().string(),
                  &rectified);
      if (!chessboardRowOffsets(left, right, pattern, &raw)) featureRowOffsets(left, right, 25, &raw);
    }
  }
  const RowErrorStats before = summarizeRowErrors(raw);
  const RowErrorStats after = summarizeRowErrors(rectified);
  printStats("raw images", before);
  printStats("rectified", after);
  if (after.samples == 0) {
    std::fprintf(stderr, "cblox-calib: no point found in both images of any pair\n");
    return 1;
  }
  if (after.median_px > max_row_error) {
    std::fprintf(stderr,
                 "cblox-calib: rectified row error %.3f px is above %.3f px: the calibration "
                 "does not fit these cameras\n",
                 after.median_px, max_row_error);
    return 1;
  }
  std::printf("ok: rectified row error %.3f px <= %.3f px\n", after.median_px, max_row_error);
  return 0;
}

int calibrate(const std::vector<ImagePair>& pairs, cv::Size pattern, double square,
              const std::string& out) {
  std::vector<std::vector<cv::Point3f>> objects;
  std::vector<std::vector<cv::Point2f>> left_points, right_points;
  std::vector<cv::Point3f> board;
  for (int r = 0; r < pattern.height; ++r) {
    for (int c = 0; c < pattern.width; ++c) {
      board.emplace_back(static_cast<float>(c * square), static_cast<float>(r * square), 0.f);
    }
  }
  cv::Size size;
  for (const ImagePair& pair : pairs) {
    const cv::Mat left = readGrey(pair.left), right = readGrey(pair.right);
    if (size.area() == 0) size = left.size();
    if (left.size() != size || right.size() != size) {
      throw InputError(pair.left + ": image size differs from the first pair's");
    }
    std::vector<cv::Point2f> corners[2];
    bool found = true;
    for (int i = 0; i < 2 && found; ++i) {
      const cv::Mat& image = i == 0 ? left : right;
      found = cv::findChessboardCorners(image, pattern, corners[i],
                                        cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
      if (found) {
        cv::cornerSubPix(image, corners[i], cv::Size(11, 11), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50,
                                          0.01));
      }
    }
    std::printf("  %s: board %s\n", std::filesystem::path(pair.left).filename().c_str(),
                found ? "found in both" : "not found in both, skipped");
    if (!found) continue;
    objects.push_back(board);
    left_points.push_back(corners[0]);
    right_points.push_back(corners[1]);
  }
  if (objects.size() < 3) {
    throw InputError("the board was found in both images of only " +
                     std::to_string(objects.size()) + " pairs; at least 3 are needed");
  }
  cv::Mat K1, D1, K2, D2, R, T, E, F;
  std::vector<cv::Mat> rvecs, tvecs;
  const double rms1 = cv::calibrateCamera(objects, left_points, size, K1, D1, rvecs, tvecs);
  const double rms2 = cv::calibrateCamera(objects, right_points, size, K2, D2, rvecs, tvecs);
  const double rms = cv::stereoCalibrate(
      objects, left_points, right_points, K1, D1, K2, D2, size, R, T, E, F,
      cv::CALIB_USE_INTRINSIC_GUESS,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-6));
  std::printf("calibrated on %zu pairs: RMS reprojection error left %.3f px, right %.3f px, "
              "stereo %.3f px; baseline %.4f (units of --square)\n",
              objects.size(), rms1, rms2, rms, cv::norm(T));
  cv::FileStorage fs(out, cv::FileStorage::WRITE);
  if (!fs.isOpened()) throw InputError(out + ": cannot write");
  fs << "image_width" << size.width << "image_height" << size.height << "M1" << K1 << "D1" << D1
     << "M2" << K2 << "D2" << D2 << "R" << R << "T" << T << "rms_px" << rms
     << "pairs_used" << static_cast<int>(objects.size());
  std::printf("wrote %s\n", out.c_str());
  return 0;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  using namespace cblox;
  CLI::App app{"cblox-calib: check a stereo calibration on image pairs (rectified row error), "
               "or calibrate a pair from chessboard images.\n"
               "Exit status: 0 ok, 1 row error above the bound, 2 usage or input error.",
               "cblox-calib"};
  app.require_subcommand(1);
  std::string calibration, list, euroc, pattern_text = "9x6", out;
  std::vector<std::string> pair_args;
  int frames = 10;
  double max_row_error = 0.5, square = 1.0;
  CLI::App* check = app.add_subcommand("check", "rectified row error of pairs");
  check->add_option("--calibration", calibration, "Kalibr camchain or OpenCV YAML/XML");
  check->add_option("--euroc", euroc, "EuRoC folder: its own calibration and images");
  check->add_option("--frames", frames, "EuRoC pairs to use, spread over the sequence")
      ->capture_default_str();
  check->add_option("--max-row-error", max_row_error, "bound on the median, pixels")
      ->capture_default_str();
  CLI::App* calib = app.add_subcommand("calibrate", "stereo calibration from chessboard pairs");
  calib->add_option("--square", square, "board square size (sets the unit of T)")
      ->capture_default_str();
  calib->add_option("--out", out, "OpenCV YAML to write")->required();
  for (CLI::App* sub : {check, calib}) {
    sub->add_option("--list", list, "OpenCV image list (left/right names alternating)");
    sub->add_option("--pair", pair_args, "LEFT RIGHT image files")->expected(2)->take_all();
    sub->add_option("--pattern", pattern_text, "chessboard inner corners COLSxROWS")
        ->capture_default_str();
  }
  if (const std::optional<int> exit = parseCommandLine(app, argc, argv)) return *exit;
  try {
    const cv::Size pattern = parsePattern(pattern_text);
    std::vector<ImagePair> pairs;
    if (!list.empty()) pairs = readImageList(list);
    for (size_t i = 0; i + 1 < pair_args.size(); i += 2) {
      pairs.push_back({pair_args[i], pair_args[i + 1]});
    }
    if (check->parsed()) {
      if (euroc.empty() == calibration.empty()) {
        throw InputError("check needs --calibration FILE with --list/--pair, or --euroc DIR");
      }
      if (euroc.empty() && pairs.empty()) throw InputError("check needs --list or --pair");
      if (frames < 1) throw InputError("--frames must be >= 1");
      return cblox::check(calibration, pairs, euroc, frames, pattern, max_row_error);
    }
    if (pairs.empty()) throw InputError("calibrate needs --list or --pair");
    if (!(square > 0)) throw InputError("--square must be > 0");
    return cblox::calibrate(pairs, pattern, square, out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cblox-calib: %s\n", e.what());
    return 2;
  }
}
