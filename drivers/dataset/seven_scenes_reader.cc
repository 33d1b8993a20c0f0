#include "drivers/dataset/seven_scenes_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <system_error>

#include <opencv2/core.hpp>

#include "core/io/text_matrix.h"
#include "drivers/dataset/image_files.h"
#include "drivers/dataset/reader_support.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

constexpr const char* kIntrinsicsFile = "camera-intrinsics.txt";
constexpr const char* kFramePrefix = "frame-";
constexpr const char* kColorSuffix = ".color.png";
constexpr const char* kColorJpegSuffix = ".color.jpg";
constexpr const char* kDepthSuffix = ".depth.png";
constexpr const char* kPoseSuffix = ".pose.txt";
constexpr uint16_t kInvalidDepthMm = 65535;
constexpr double kMetresPerMm = 1e-3;  // as a float, d * 1e-3 equals d / 1000.0 for all uint16 d

using dataset_detail::isFile;
using dataset_detail::setError;

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The files of a frame, by kind: colour (PNG), depth, pose, colour (JPEG).
enum FileKind { kColorPng = 0, kDepth = 1, kPose = 2, kColorJpeg = 3, kKinds = 4 };
constexpr const char* kSuffixes[kKinds] = {kColorSuffix, kDepthSuffix, kPoseSuffix,
                                           kColorJpegSuffix};

// Parses "frame-<digits><suffix>" into the digits and which file it is (a FileKind). Returns
// false for any other name.
bool parseFrameName(const std::string& name, std::string* digits, int* kind) {
  const std::string prefix = kFramePrefix;
  if (name.rfind(prefix, 0) != 0) return false;
  for (int k = 0; k < kKinds; ++k) {
    if (!endsWith(name, kSuffixes[k])) continue;
    const size_t length = name.size() - prefix.size() - std::string(kSuffixes[k]).size();
    if (length == 0 || length > 18) return false;
    *digits = name.substr(prefix.size(), length);
    if (!std::all_of(digits->begin(), digits->end(),
                     [](unsigned char c) { return std::isdigit(c) != 0; })) {
      return false;
    }
    *kind = k;
    return true;
  }
  return false;
}

// Reads and validates a pose file: 16 numbers forming a rigid transform (see
// validateRigidTransform).
bool readPose(const std::string& path, Transformationd* T, std::string* error) {
  const std::optional<Eigen::MatrixXd> m = readTextMatrix(path, 4, 4, error);
  if (!m) return false;
  const Eigen::Matrix4d M = *m;
  const std::string invalid = validateRigidTransform(M);
  if (!invalid.empty()) return setError(error, path + ": " + invalid);
  *T = Transformationd::fromMatrix(M);
  return true;
}

// Loads a 16-bit single-channel depth PNG without decoding its values.
bool loadDepthMm(const std::string& path, cv::Mat* mm, std::string* error) {
  return readDepthUnits(path, "16-bit single-channel (millimetres)", mm, error);
}

}  // namespace

std::optional<SevenScenesReader> SevenScenesReader::open(const std::string& folder,
                                                         std::string* error) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    setError(error, folder + ": not a readable directory");
    return std::nullopt;
  }

  // Intrinsics.
  const std::string intrinsics_path = (fs::path(folder) / kIntrinsicsFile).string();
  if (!isFile(intrinsics_path)) {
    setError(error, intrinsics_path + ": camera intrinsics file is missing");
    return std::nullopt;
  }
  const std::optional<Eigen::MatrixXd> K = readTextMatrix(intrinsics_path, 3, 3, error);
  if (!K) return std::nullopt;

  // Frames: group the three files of each frame number.
  struct Found {
    std::string digits;
    bool present[kKinds] = {false, false, false, false};
  };
  std::map<int64_t, Found> found;
  fs::directory_iterator it(folder, ec);
  if (ec) {
    setError(error, folder + ": cannot list directory: " + ec.message());
    return std::nullopt;
  }
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    const fs::directory_entry& entry = *it;
    std::string digits;
    int kind = 0;
    if (!parseFrameName(entry.path().filename().string(), &digits, &kind)) continue;
    const int64_t number = std::stoll(digits);
    Found& f = found[number];
    if (!f.digits.empty() && f.digits != digits) {
      setError(error, folder + ": frame number " + std::to_string(number) + " is spelled both '" +
                          f.digits + "' and '" + digits + "'");
      return std::nullopt;
    }
    f.digits = digits;
    f.present[kind] = true;
  }
  if (ec) {
    setError(error, folder + ": cannot list directory: " + ec.message());
    return std::nullopt;
  }
  if (found.empty()) {
    setError(error, folder + ": no frame-NNNNNN.{color.png|color.jpg,depth.png,pose.txt} files");
    return std::nullopt;
  }

  SevenScenesReader reader;
  reader.folder_ = folder;
  for (const auto& [number, f] : found) {
    const std::string stem = (fs::path(folder) / (kFramePrefix + f.digits)).string();
    const std::string incomplete =
        " is missing (frame " + std::to_string(number) + " is incomplete)";
    if (!f.present[kColorPng] && !f.present[kColorJpeg]) {
      setError(error, stem + kColorSuffix + ": file (or " + kColorJpegSuffix + ")" + incomplete);
      return std::nullopt;
    }
    for (const int k : {kDepth, kPose}) {
      if (!f.present[k]) {
        setError(error, stem + kSuffixes[k] + ": file" + incomplete);
        return std::nullopt;
      }
    }
    reader.frames_.push_back(
        {number, stem, f.present[kColorPng] ? kColorSuffix : kColorJpegSuffix});
  }

  // Image size from the first depth image.
  const std::string first_depth = reader.frames_.front().stem + kDepthSuffix;
  cv::Mat mm;
  if (!loadDepthMm(first_depth, &mm, error)) return std::nullopt;
  try {
    reader.intrinsics_ = PinholeCamera::fromK(Eigen::Matrix3d(*K), mm.cols, mm.rows);
  } catch (const std::exception& e) {
    setError(error, intrinsics_path + ": " + e.what());
    return std::nullopt;
  }
  const std::string invalid = validate(reader.intrinsics_);
  if (!invalid.empty()) {
    setError(error, intrinsics_path + ": invalid intrinsics: " + invalid);
    return std::nullopt;
  }
  return reader;
}

bool SevenScenesReader::read(size_t i, SevenScenesFrame* frame, std::string* error) const {
  if (i >= frames_.size()) {
    return setError(error, folder_ + ": frame " + std::to_string(i) + " out of range (size " +
                               std::to_string(frames_.size()) + ")");
  }
  const FrameFiles& files = frames_[i];

  SevenScenesFrame out;
  out.index = files.number;
  if (!readPose(files.stem + kPoseSuffix, &out.T_G_C, error)) return false;

  const std::string depth_path = files.stem + kDepthSuffix;
  cv::Mat mm;
  if (!loadDepthMm(depth_path, &mm, error)) return false;
  if (!checkImageSize(depth_path, mm, intrinsics_.width, intrinsics_.height, "the intrinsics'",
                      error)) {
    return false;
  }
  out.depth = depthFromUnits(mm, kMetresPerMm, kInvalidDepthMm);

  if (!readColorImage(files.stem + files.color_suffix, mm.cols, mm.rows, "the depth image's",
                      &out.color, error)) {
    return false;
  }

  *frame = std::move(out);
  return true;
}

}  // namespace cblox
