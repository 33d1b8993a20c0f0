#include "drivers/dataset/kitti_odometry_reader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <system_error>
#include <utility>

#include <opencv2/core.hpp>

#include "core/io/text_fields.h"
#include "core/io/text_matrix.h"
#include "drivers/dataset/image_files.h"
#include "drivers/dataset/reader_support.h"

namespace cblox {
namespace {

using dataset_detail::at;
using dataset_detail::isDirectory;
using dataset_detail::isFile;
using dataset_detail::join;
using dataset_detail::parseDouble;
using dataset_detail::setError;

using Row12 = std::array<double, 12>;

// A line's whitespace-separated tokens.
std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  std::string token;
  while (in >> token) out.push_back(token);
  return out;
}

// Exactly 12 finite numbers from `fields`, or a message.
bool parseRow12(const std::vector<std::string>& fields, Row12* row, std::string* what) {
  if (fields.size() != 12) {
    *what = "expected 12 numbers, got " + std::to_string(fields.size());
    return false;
  }
  for (size_t k = 0; k < 12; ++k) {
    if (!parseDouble(fields[k], &(*row)[k])) {
      *what = "'" + fields[k] + "' is not a finite number";
      return false;
    }
  }
  return true;
}

// calib.txt: "LABEL: n1 .. n12" rows by label (P0 .. P3 and Tr checked for 12 numbers; other
// labels kept as read and not used), with the line each came from.
bool readCalib(const std::string& path, std::map<std::string, std::pair<Row12, size_t>>* rows,
               std::vector<std::string>* unused, std::string* error) {
  std::ifstream in(path);
  if (!in) return setError(error, path + ": cannot open");
  std::string line;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (trimBlanks(line).empty()) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) {
      return setError(error, at(path, number) + "expected 'LABEL: 12 numbers'");
    }
    const std::string label = trimBlanks(line.substr(0, colon));
    if (label.empty() || label.find_first_of(" \t") != std::string::npos) {
      return setError(error, at(path, number) + "expected 'LABEL: 12 numbers'");
    }
    if (rows->count(label) > 0) return setError(error, at(path, number) + label + " repeated");
    Row12 row{};
    std::string what;
    if (!parseRow12(tokens(line.substr(colon + 1)), &row, &what)) {
      if (label.size() == 2 && label[0] == 'P' && label[1] >= '0' && label[1] <= '3') {
        return setError(error, at(path, number) + label + ": " + what);
      }
      unused->push_back(label);  // another tool's row (e.g. KITTI raw's); not ours to judge
      continue;
    }
    rows->emplace(label, std::make_pair(row, number));
  }
  return true;
}

// P0 = K [I | 0] and P1 = K [I | (-b, 0, 0)] * fx: the intrinsics and the baseline.
bool readRectifiedPair(const std::string& path,
                       const std::map<std::string, std::pair<Row12, size_t>>& rows,
                       RectifiedStereoCalibration* calibration, std::string* error) {
  for (const char* label : {"P0", "P1"}) {
    if (rows.count(label) == 0) return setError(error, path + ": " + label + " is missing");
  }
  const auto& [p0, line0] = rows.at("P0");
  const auto& [p1, line1] = rows.at("P1");
  const double fx = p0[0], fy = p0[5], cx = p0[2], cy = p0[6];
  if (!(fx > 0.0) || !(fy > 0.0)) {
    return setError(error, at(path, line0) + "P0: fx and fy must be > 0");
  }
  // Tolerances relative to the focal length (the files hold 7 significant digits).
  const double eps = 1e-6 * fx;
  const auto zero = [eps](double v) { return std::abs(v) <= eps; };
  if (!zero(p0[1]) || !zero(p0[4]) || !zero(p0[8]) || !zero(p0[9]) ||
      std::abs(p0[10] - 1.0) > 1e-9) {
    return setError(error,
                    at(path, line0) + "P0 must be K [I | 0] with K = [fx 0 cx; 0 fy cy; 0 0 1]");
  }
  if (!zero(p0[3]) || !zero(p0[7]) || !zero(p0[11])) {
    return setError(
        error, at(path, line0) + "P0 has a translation: camera 0 must be the rectified reference");
  }
  for (const int k : {0, 1, 2, 4, 5, 6, 8, 9, 10}) {
    if (std::abs(p1[static_cast<size_t>(k)] - p0[static_cast<size_t>(k)]) > eps) {
      return setError(error,
                      at(path, line1) + "P1's intrinsics differ from P0's: not a rectified pair");
    }
  }
  if (!zero(p1[7]) || !zero(p1[11])) {
    return setError(error,
                    at(path, line1) + "P1's translation is not along x: not a rectified pair");
  }
  const double baseline = -p1[3] / fx;
  if (!(baseline > 0.0)) {
    return setError(error, at(path, line1) +
                               "P1 has no baseline: -P1[0][3] / fx must be > 0, got " +
                               std::to_string(baseline));
  }
  calibration->intrinsics.fx = fx;
  calibration->intrinsics.fy = fy;
  calibration->intrinsics.cx = cx;
  calibration->intrinsics.cy = cy;
  calibration->baseline_m = baseline;
  calibration->T_B_L = Transformationd();
  return true;
}

// The numbers of the NNNNNN.png files of `dir`, sorted; anything else in it is ignored.
bool listImages(const std::string& dir, std::vector<long>* numbers, std::string* error) {
  std::error_code ec;
  std::filesystem::directory_iterator it(dir, ec);
  if (ec) return setError(error, dir + ": cannot list: " + ec.message());
  for (const auto& entry : it) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() != ".png") continue;
    const std::string stem = entry.path().stem().string();
    if (stem.size() != 6 || stem.find_first_not_of("0123456789") != std::string::npos) {
      return setError(error, join(dir, name) + ": not named NNNNNN.png (six digits)");
    }
    numbers->push_back(std::stol(stem));
  }
  std::sort(numbers->begin(), numbers->end());
  return true;
}

std::string imageName(size_t i) {
  char name[16];
  std::snprintf(name, sizeof(name), "%06zu.png", i);
  return name;
}

// Both folders hold 000000.png .. N-1 without a gap.
bool pairImages(const std::string& folder, size_t* count, std::string* error) {
  std::vector<long> left, right;
  const std::string dir0 = join(folder, "image_0"), dir1 = join(folder, "image_1");
  if (!listImages(dir0, &left, error) || !listImages(dir1, &right, error)) return false;
  if (left.empty()) return setError(error, dir0 + ": no NNNNNN.png image");
  for (size_t i = 0; i < std::max(left.size(), right.size()); ++i) {
    const long expected = static_cast<long>(i);
    if (i >= left.size() || left[i] != expected) {
      return setError(error, join(dir0, imageName(i)) + ": missing" +
                                 (i < right.size() && right[i] == expected
                                      ? " (" + join(dir1, imageName(i)) + " has no partner)"
                                      : std::string()));
    }
    if (i >= right.size() || right[i] != expected) {
      return setError(error, join(dir1, imageName(i)) + ": missing (" + join(dir0, imageName(i)) +
                                 " has no partner)");
    }
  }
  *count = left.size();
  return true;
}

// Calls row(line number, tokens) for every non-blank line of `path` (false from it ends the
// reading), then checks that there were `count` rows of `what`.
template <typename RowFn>
bool readRows(const std::string& path, size_t count, const char* what, std::string* error,
              RowFn row) {
  std::ifstream in(path);
  if (!in) return setError(error, path + ": cannot open");
  std::string line;
  size_t number = 0, rows = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::vector<std::string> fields = tokens(line);
    if (fields.empty()) continue;
    if (!row(number, fields)) return false;
    ++rows;
  }
  if (rows != count) {
    return setError(error, path + ": " + std::to_string(rows) + " " + what + " for " +
                               std::to_string(count) + " image pairs");
  }
  return true;
}

bool readTimes(const std::string& path, size_t count, std::vector<int64_t>* times_ns,
               std::string* error) {
  double previous = -1.0;
  return readRows(path, count, "times", error, [&](size_t number, const auto& fields) {
    double t = 0.0;
    if (fields.size() != 1 || !parseDouble(fields[0], &t) || t < 0.0 || t > 1e9) {
      std::string text;
      for (const std::string& f : fields) text += (text.empty() ? "" : " ") + f;
      return setError(error,
                      at(path, number) + "expected one time in seconds (>= 0), got '" + text + "'");
    }
    if (!(t > previous)) {
      return setError(error, at(path, number) + "times must increase (" + fields[0] + " after " +
                                 std::to_string(previous) + ")");
    }
    previous = t;
    times_ns->push_back(std::llround(t * 1e9));
    return true;
  });
}

bool readPoses(const std::string& path, size_t count, std::vector<Transformationd>* poses,
               std::string* error) {
  return readRows(path, count, "poses", error, [&](size_t number, const auto& fields) {
    Row12 row{};
    std::string what;
    if (!parseRow12(fields, &row, &what)) return setError(error, at(path, number) + what);
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) M(r, c) = row[static_cast<size_t>(r * 4 + c)];
    }
    if (const std::string invalid = validateRigidTransform(M); !invalid.empty()) {
      return setError(error, at(path, number) + invalid);
    }
    poses->push_back(Transformationd::fromMatrix(M));
    return true;
  });
}

}  // namespace

std::optional<KittiOdometryReader> KittiOdometryReader::open(const std::string& folder,
                                                             std::string* error) {
  if (!isDirectory(folder)) {
    setError(error, folder +
                        ": not a folder (a KITTI odometry sequence: image_0/, image_1/, "
                        "calib.txt, times.txt)");
    return std::nullopt;
  }
  KittiOdometryReader reader;
  reader.folder_ = folder;
  for (const char* dir : {"image_0", "image_1"}) {
    if (!isDirectory(join(folder, dir))) {
      setError(error, join(folder, dir) + ": missing (the left and right grey images)");
      return std::nullopt;
    }
  }
  for (const char* file : {"calib.txt", "times.txt"}) {
    if (!isFile(join(folder, file))) {
      setError(error, join(folder, file) + ": missing");
      return std::nullopt;
    }
  }
  const std::string calib_path = join(folder, "calib.txt");
  std::map<std::string, std::pair<Row12, size_t>> rows;
  std::vector<std::string> unused;
  if (!readCalib(calib_path, &rows, &unused, error) ||
      !readRectifiedPair(calib_path, rows, &reader.calibration_, error)) {
    return std::nullopt;
  }
  for (const auto& [label, row] : rows) {
    if (label != "P0" && label != "P1") unused.push_back(label);
  }
  if (!unused.empty()) {
    std::string list;
    for (const std::string& label : unused) list += (list.empty() ? "" : ", ") + label;
    reader.notes_.push_back(calib_path + ": " + list +
                            " read and not used (the grey pair is P0 and P1)");
  }

  size_t count = 0;
  if (!pairImages(folder, &count, error)) return std::nullopt;
  cv::Mat first;
  if (!readGrayImage(reader.leftImagePath(0), &first, error)) return std::nullopt;
  PinholeIntrinsics& K = reader.calibration_.intrinsics;
  K.width = first.cols;
  K.height = first.rows;
  if (!(K.cx >= 0.0 && K.cx <= K.width && K.cy >= 0.0 && K.cy <= K.height)) {
    setError(error, at(calib_path, rows.at("P0").second) + "principal point (" +
                        std::to_string(K.cx) + ", " + std::to_string(K.cy) + ") lies outside the " +
                        describeSize(K.width, K.height) + " images");
    return std::nullopt;
  }
  if (!readTimes(join(folder, "times.txt"), count, &reader.times_ns_, error)) return std::nullopt;
  if (count > 1) {
    reader.rate_hz_ =
        static_cast<double>(count - 1) /
        (static_cast<double>(reader.times_ns_.back() - reader.times_ns_.front()) * 1e-9);
  }

  // Ground truth: in the folder, or where KITTI's dataset/ layout keeps it.
  const std::filesystem::path sequence = std::filesystem::path(folder).lexically_normal();
  const std::string name =
      (sequence.has_filename() ? sequence : sequence.parent_path()).filename().string();
  for (const std::string& candidate :
       {join(folder, "poses.txt"),
        join(join(join(folder, ".."), ".."), "poses/" + name + ".txt")}) {
    if (!isFile(candidate)) continue;
    reader.ground_truth_path_ = std::filesystem::path(candidate).lexically_normal().string();
    if (!readPoses(reader.ground_truth_path_, count, &reader.poses_, error)) return std::nullopt;
    reader.notes_.push_back("ground truth: " + reader.ground_truth_path_);
    break;
  }
  if (reader.poses_.empty()) {
    reader.notes_.push_back("no ground truth (neither poses.txt nor ../../poses/" + name + ".txt)");
  }
  return reader;
}

std::string KittiOdometryReader::leftImagePath(size_t i) const {
  return join(join(folder_, "image_0"), imageName(i));
}

std::string KittiOdometryReader::rightImagePath(size_t i) const {
  return join(join(folder_, "image_1"), imageName(i));
}

bool KittiOdometryReader::read(size_t i, KittiStereoFrame* frame, std::string* error) const {
  if (i >= size()) {
    return setError(error, folder_ + ": frame " + std::to_string(i) + " out of range (size " +
                               std::to_string(size()) + ")");
  }
  const int width = calibration_.intrinsics.width, height = calibration_.intrinsics.height;
  KittiStereoFrame out;
  out.timestamp_ns = times_ns_[i];
  if (!poses_.empty()) out.T_G_L = poses_[i];
  const auto load = [&](const std::string& path, GrayImage* image) {
    cv::Mat raw;
    if (!readGrayImage(path, &raw, error)) return false;
    if (!checkImageSize(path, raw, width, height, "the first left image's", error)) return false;
    *image = GrayImage(width, height);
    cv::Mat view(height, width, CV_8UC1, image->data.data());
    raw.copyTo(view);
    return true;
  };
  if (!load(leftImagePath(i), &out.left) || !load(rightImagePath(i), &out.right)) return false;
  *frame = std::move(out);
  return true;
}

}  // namespace cblox
