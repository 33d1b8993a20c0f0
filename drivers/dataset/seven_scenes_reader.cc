#include "drivers/dataset/seven_scenes_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <system_error>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "drivers/dataset/text_matrix.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

constexpr const char* kIntrinsicsFile = "camera-intrinsics.txt";
constexpr const char* kFramePrefix = "frame-";
constexpr const char* kColorSuffix = ".color.png";
constexpr const char* kDepthSuffix = ".depth.png";
constexpr const char* kPoseSuffix = ".pose.txt";
constexpr double kOrthonormalityTolerance = 1e-3;
constexpr double kLastRowTolerance = 1e-6;
constexpr uint16_t kInvalidDepthMm = 65535;

bool setError(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Parses "frame-<digits><suffix>" into the digits and which of the three files it is
// (0 colour, 1 depth, 2 pose). Returns false for any other name.
bool parseFrameName(const std::string& name, std::string* digits, int* kind) {
  const std::string prefix = kFramePrefix;
  if (name.rfind(prefix, 0) != 0) return false;
  const char* suffixes[] = {kColorSuffix, kDepthSuffix, kPoseSuffix};
  for (int k = 0; k < 3; ++k) {
    if (!endsWith(name, suffixes[k])) continue;
    const size_t length = name.size() - prefix.size() - std::string(suffixes[k]).size();
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

std::string describeType(const cv::Mat& image) {
  std::ostringstream os;
  const int depth = image.depth();
  const int bits = depth == CV_8U || depth == CV_8S     ? 8
                   : depth == CV_16U || depth == CV_16S ? 16
                   : depth == CV_64F                    ? 64
                                                        : 32;
  os << bits << "-bit with " << image.channels() << " channel(s)";
  return os.str();
}

// True if path names an existing regular file; never throws.
bool isFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

std::string describeSize(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Reads and validates a pose file: 16 numbers, last row 0 0 0 1, orthonormal right-handed
// rotation within kOrthonormalityTolerance.
bool readPose(const std::string& path, Transformationd* T, std::string* error) {
  const std::optional<Eigen::MatrixXd> m = readTextMatrix(path, 4, 4, error);
  if (!m) return false;
  const Eigen::Matrix4d M = *m;
  if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kLastRowTolerance) {
    std::ostringstream os;
    os << path << ": last row must be 0 0 0 1, got " << M.row(3);
    return setError(error, os.str());
  }
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  const double deviation = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kOrthonormalityTolerance) {
    std::ostringstream os;
    os << path << ": rotation is not orthonormal (max |R^T R - I| = " << deviation << ", tolerance "
       << kOrthonormalityTolerance << ")";
    return setError(error, os.str());
  }
  if (R.determinant() < 0) return setError(error, path + ": rotation is a reflection (det < 0)");
  *T = Transformationd::fromMatrix(M);
  return true;
}

// Loads a 16-bit single-channel depth PNG without decoding its values.
bool loadDepthMm(const std::string& path, cv::Mat* mm, std::string* error) {
  if (!isFile(path)) return setError(error, path + ": depth image is missing");
  *mm = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (mm->empty()) return setError(error, path + ": cannot read depth image");
  if (mm->type() != CV_16UC1) {
    return setError(error, path +
                               ": depth image must be 16-bit single-channel (millimetres), got " +
                               describeType(*mm));
  }
  return true;
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
    bool present[3] = {false, false, false};
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
    setError(error, folder + ": no frame-NNNNNN.{color.png,depth.png,pose.txt} files");
    return std::nullopt;
  }

  SevenScenesReader reader;
  reader.folder_ = folder;
  const char* suffixes[] = {kColorSuffix, kDepthSuffix, kPoseSuffix};
  for (const auto& [number, f] : found) {
    const std::string stem = (fs::path(folder) / (kFramePrefix + f.digits)).string();
    for (int k = 0; k < 3; ++k) {
      if (!f.present[k]) {
        setError(error, stem + suffixes[k] + ": file is missing (frame " + std::to_string(number) +
                            " is incomplete)");
        return std::nullopt;
      }
    }
    reader.frames_.push_back({number, stem});
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
  if (mm.cols != intrinsics_.width || mm.rows != intrinsics_.height) {
    return setError(error, depth_path + ": size " + describeSize(mm.cols, mm.rows) +
                               " does not match the intrinsics' " +
                               describeSize(intrinsics_.width, intrinsics_.height));
  }
  out.depth = DepthImage(mm.cols, mm.rows, 0.0f);
  for (int v = 0; v < mm.rows; ++v) {
    const uint16_t* row = mm.ptr<uint16_t>(v);
    for (int u = 0; u < mm.cols; ++u) {
      const uint16_t d = row[u];
      out.depth(u, v) = (d == 0 || d == kInvalidDepthMm) ? 0.0f : static_cast<float>(d / 1000.0);
    }
  }

  const std::string color_path = files.stem + kColorSuffix;
  if (!isFile(color_path)) return setError(error, color_path + ": colour image is missing");
  const cv::Mat bgr = cv::imread(color_path, cv::IMREAD_COLOR);
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    return setError(error, color_path + ": cannot read colour image");
  }
  if (bgr.cols != mm.cols || bgr.rows != mm.rows) {
    return setError(error, color_path + ": size " + describeSize(bgr.cols, bgr.rows) +
                               " does not match the depth image's " +
                               describeSize(mm.cols, mm.rows));
  }
  out.color = ColorImage(bgr.cols, bgr.rows);
  for (int v = 0; v < bgr.rows; ++v) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < bgr.cols; ++u) out.color(u, v) = Color{row[u][2], row[u][1], row[u][0]};
  }

  *frame = std::move(out);
  return true;
}

}  // namespace cblox
