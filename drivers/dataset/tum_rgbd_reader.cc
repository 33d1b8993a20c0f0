#include "drivers/dataset/tum_rgbd_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>
#include <tuple>
#include <utility>

#include <opencv2/core.hpp>

#include "core/io/tum_trajectory.h"
#include "drivers/dataset/image_files.h"
#include "drivers/dataset/reader_support.h"
#include "core/io/text_matrix.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

constexpr const char* kRgbList = "rgb.txt";
constexpr const char* kDepthList = "depth.txt";
constexpr const char* kGroundTruth = "groundtruth.txt";
constexpr const char* kIntrinsicsFile = "camera-intrinsics.txt";
// TUM's documented intrinsics for uncalibrated use ("ROS default"), 640x480.
constexpr double kDefaultFocal = 525.0;
constexpr double kDefaultCx = 319.5;
constexpr double kDefaultCy = 239.5;

using dataset_detail::at;
using dataset_detail::isFile;
using dataset_detail::join;
using dataset_detail::setError;

std::string formatSeconds(double t) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.6f", t);
  return buffer;
}

// Shortest round-trip-ish form for messages: 0.02 rather than 0.020000.
std::string formatNumber(double value) {
  std::ostringstream os;
  os << value;
  return os.str();
}

struct ListEntry {
  double timestamp_s = 0.0;
  std::string filename;  // relative to the folder, as written in the list
};

// Reads a TUM image list: "timestamp filename" per line, '#' comments, empty lines skipped.
bool readImageList(const std::string& path, std::vector<ListEntry>* entries, std::string* error) {
  if (!isFile(path)) return setError(error, path + ": image list is missing");
  std::ifstream in(path);
  if (!in) return setError(error, path + ": cannot open file");
  entries->clear();
  std::string line;
  size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::vector<std::string> tokens;
    std::string token;
    while (fields >> token) tokens.push_back(token);
    if (tokens.size() != 2) {
      return setError(error, at(path, line_number) + "expected 'timestamp filename', got '" +
                                 line.substr(first) + "'");
    }
    ListEntry entry;
    char* end = nullptr;
    entry.timestamp_s = std::strtod(tokens[0].c_str(), &end);
    if (end != tokens[0].c_str() + tokens[0].size() || !std::isfinite(entry.timestamp_s)) {
      return setError(error, at(path, line_number) + "timestamp '" + tokens[0] +
                                 "' is not a finite number (seconds)");
    }
    if (!entries->empty() && entry.timestamp_s <= entries->back().timestamp_s) {
      return setError(error, at(path, line_number) + "timestamp " + tokens[0] +
                                 " does not increase (previous " +
                                 formatSeconds(entries->back().timestamp_s) + ")");
    }
    entry.filename = tokens[1];
    entries->push_back(std::move(entry));
  }
  if (in.bad()) return setError(error, path + ": read error");
  return true;
}

// Loads a 16-bit single-channel depth image without decoding its values.
bool loadDepthUnits(const std::string& path, cv::Mat* units, std::string* error) {
  return readDepthUnits(path, "a 16-bit single-channel PNG", units, error);
}

}  // namespace

std::string TumRgbdReader::Options::validate() const {
  if (!(depth_scale > 0) || !std::isfinite(depth_scale)) {
    return "depth_scale must be > 0 and finite, got " + std::to_string(depth_scale);
  }
  if (!(max_association_difference_s > 0) || !std::isfinite(max_association_difference_s)) {
    return "max_association_difference_s must be > 0 and finite, got " +
           std::to_string(max_association_difference_s);
  }
  if (!(groundtruth_max_gap_s > 0) || !std::isfinite(groundtruth_max_gap_s)) {
    return "groundtruth_max_gap_s must be > 0 and finite, got " +
           std::to_string(groundtruth_max_gap_s);
  }
  if (intrinsics) {
    PinholeIntrinsics in = *intrinsics;
    if (in.width == 0 && in.height == 0) in.width = in.height = 1;  // taken from the images
    const std::string invalid = cblox::validate(in);
    if (!invalid.empty()) return "intrinsics: " + invalid;
  }
  return {};
}

std::optional<TumRgbdReader> TumRgbdReader::open(const std::string& folder, const Options& options,
                                                 std::string* error) {
  const std::string invalid_options = options.validate();
  if (!invalid_options.empty()) {
    setError(error, "TumRgbdReader::Options: " + invalid_options);
    return std::nullopt;
  }
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    setError(error, folder + ": not a readable directory");
    return std::nullopt;
  }
  TumRgbdReader reader;
  reader.folder_ = folder;
  reader.depth_scale_ = options.depth_scale;

  // Image lists; entries whose file is missing are dropped.
  std::vector<ListEntry> depth_list;
  std::vector<ListEntry> rgb_list;
  if (!readImageList(join(folder, kDepthList), &depth_list, error)) return std::nullopt;
  if (!readImageList(join(folder, kRgbList), &rgb_list, error)) return std::nullopt;
  const auto dropMissing = [&](std::vector<ListEntry>* list, const std::string& what) {
    std::vector<ListEntry> kept;
    for (ListEntry& entry : *list) {
      if (isFile(join(folder, entry.filename))) {
        kept.push_back(std::move(entry));
      } else {
        reader.skipped_.push_back(entry.filename + ": missing, " + what + " " +
                                  formatSeconds(entry.timestamp_s) + " skipped");
      }
    }
    *list = std::move(kept);
  };
  const size_t depth_listed = depth_list.size();
  dropMissing(&depth_list, "depth frame");
  dropMissing(&rgb_list, "colour image");
  if (depth_list.empty()) {
    setError(error, join(folder, kDepthList) + ": no depth image (" + std::to_string(depth_listed) +
                        " listed, none found on disk)");
    return std::nullopt;
  }

  // Association as TUM's associate.py: all pairs closer than the maximum difference, taken
  // greedily by increasing difference, each image used at most once.
  const double max_difference = options.max_association_difference_s;
  std::vector<std::tuple<double, size_t, size_t>> candidates;  // |dt|, depth index, rgb index
  for (size_t d = 0; d < depth_list.size(); ++d) {
    const double t = depth_list[d].timestamp_s;
    auto it = std::lower_bound(
        rgb_list.begin(), rgb_list.end(), t - max_difference,
        [](const ListEntry& entry, double time) { return entry.timestamp_s < time; });
    for (; it != rgb_list.end() && it->timestamp_s < t + max_difference; ++it) {
      const double difference = std::abs(it->timestamp_s - t);
      if (difference < max_difference) {
        candidates.emplace_back(difference, d, static_cast<size_t>(it - rgb_list.begin()));
      }
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<std::optional<size_t>> rgb_of_depth(depth_list.size());
  std::vector<bool> rgb_used(rgb_list.size(), false);
  for (const auto& [difference, d, r] : candidates) {
    if (rgb_of_depth[d] || rgb_used[r]) continue;
    rgb_of_depth[d] = r;
    rgb_used[r] = true;
  }

  size_t without_color = 0;
  for (size_t d = 0; d < depth_list.size(); ++d) {
    FrameFiles files;
    files.timestamp_s = depth_list[d].timestamp_s;
    files.depth_path = join(folder, depth_list[d].filename);
    if (rgb_of_depth[d]) {
      const ListEntry& rgb = rgb_list[*rgb_of_depth[d]];
      files.color_timestamp_s = rgb.timestamp_s;
      files.color_path = join(folder, rgb.filename);
    } else {
      ++without_color;
      reader.skipped_.push_back(depth_list[d].filename + ": no colour image within " +
                                formatNumber(max_difference) + " s, frame " +
                                formatSeconds(files.timestamp_s) + " played without colour");
    }
    reader.frames_.push_back(std::move(files));
  }
  if (without_color > 0) {
    reader.notes_.push_back(std::to_string(without_color) + " of " +
                            std::to_string(reader.frames_.size()) +
                            " frames have no colour image within " + formatNumber(max_difference) +
                            " s (played without colour)");
  }
  const size_t unused_rgb =
      static_cast<size_t>(std::count(rgb_used.begin(), rgb_used.end(), false));
  if (unused_rgb > 0) {
    reader.notes_.push_back(std::to_string(unused_rgb) + " of " + std::to_string(rgb_list.size()) +
                            " colour images are not associated with a depth image");
  }
  const size_t missing = reader.skipped_.size() - without_color;
  if (missing > 0) {
    reader.notes_.push_back(std::to_string(missing) +
                            " listed images are missing on disk, see skipped()");
  }

  // Ground truth.
  const std::string groundtruth_path = join(folder, kGroundTruth);
  if (isFile(groundtruth_path)) {
    const std::optional<StampedTrajectory> trajectory = readTumTrajectory(groundtruth_path, error);
    if (!trajectory) return std::nullopt;
    reader.has_groundtruth_ = true;
    size_t without = 0;
    for (FrameFiles& files : reader.frames_) {
      files.T_G_C = interpolatePose(*trajectory, files.timestamp_s, options.groundtruth_max_gap_s);
      if (!files.T_G_C) ++without;
    }
    if (without > 0) {
      std::ostringstream os;
      os << without << " of " << reader.frames_.size() << " frames have no ground truth "
         << "(outside " << kGroundTruth << "'s time range or in a gap > "
         << options.groundtruth_max_gap_s << " s)";
      reader.notes_.push_back(os.str());
    }
  } else {
    reader.notes_.push_back(std::string("no ground truth: ") + kGroundTruth + " absent");
  }

  // Intrinsics; the image size comes from the first depth image.
  cv::Mat first;
  if (!loadDepthUnits(reader.frames_.front().depth_path, &first, error)) return std::nullopt;
  const std::string intrinsics_path = join(folder, kIntrinsicsFile);
  std::string source;
  if (options.intrinsics) {
    reader.intrinsics_ = *options.intrinsics;
    if (reader.intrinsics_.width == 0 && reader.intrinsics_.height == 0) {
      reader.intrinsics_.width = first.cols;
      reader.intrinsics_.height = first.rows;
    }
    source = "TumRgbdReader::Options::intrinsics";
  } else if (isFile(intrinsics_path)) {
    const std::optional<Eigen::MatrixXd> K = readTextMatrix(intrinsics_path, 3, 3, error);
    if (!K) return std::nullopt;
    try {
      reader.intrinsics_ = PinholeCamera::fromK(Eigen::Matrix3d(*K), first.cols, first.rows);
    } catch (const std::exception& e) {
      setError(error, intrinsics_path + ": " + e.what());
      return std::nullopt;
    }
    source = intrinsics_path;
  } else {
    reader.intrinsics_.fx = kDefaultFocal;
    reader.intrinsics_.fy = kDefaultFocal;
    reader.intrinsics_.cx = kDefaultCx;
    reader.intrinsics_.cy = kDefaultCy;
    reader.intrinsics_.width = first.cols;
    reader.intrinsics_.height = first.rows;
    source = "TUM's default intrinsics";
    reader.notes_.push_back(std::string("no intrinsics given and ") + kIntrinsicsFile +
                            " absent: using TUM's default fx = fy = 525, cx = 319.5, cy = 239.5");
  }
  const std::string invalid = validate(reader.intrinsics_);
  if (!invalid.empty()) {
    setError(error, source + ": invalid intrinsics: " + invalid);
    return std::nullopt;
  }
  return reader;
}

bool TumRgbdReader::read(size_t i, TumRgbdFrame* frame, std::string* error) const {
  if (i >= frames_.size()) {
    return setError(error, folder_ + ": frame " + std::to_string(i) + " out of range (size " +
                               std::to_string(frames_.size()) + ")");
  }
  const FrameFiles& files = frames_[i];

  TumRgbdFrame out;
  out.timestamp_s = files.timestamp_s;
  out.color_timestamp_s = files.color_timestamp_s;
  out.T_G_C = files.T_G_C;

  cv::Mat units;
  if (!loadDepthUnits(files.depth_path, &units, error)) return false;
  if (!checkImageSize(files.depth_path, units, intrinsics_.width, intrinsics_.height,
                      "the intrinsics'", error)) {
    return false;
  }
  out.depth = depthFromUnits(units, depth_scale_);

  if (!files.color_path.empty() && !readColorImage(files.color_path, units.cols, units.rows,
                                                   "the depth image's", &out.color, error)) {
    return false;
  }

  *frame = std::move(out);
  return true;
}

}  // namespace cblox
