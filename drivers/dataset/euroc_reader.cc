#include "drivers/dataset/euroc_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <tuple>
#include <utility>

#include <yaml-cpp/yaml.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/io/text_fields.h"
#include "core/io/text_matrix.h"
#include "core/io/tum_trajectory.h"
#include "drivers/calibration/stereo_rectifier.h"
#include "drivers/dataset/image_files.h"
#include "drivers/dataset/reader_support.h"

namespace cblox {

namespace {

constexpr const char* kMav0 = "mav0";
constexpr const char* kSensorFile = "sensor.yaml";
constexpr const char* kImageList = "data.csv";
constexpr const char* kImageFolder = "data";
constexpr const char* kGroundTruth = "state_groundtruth_estimate0/data.csv";
constexpr const char* kRadTan = "radial-tangential";
constexpr const char* kEquidistant = "equidistant";
constexpr double kQuaternionNormTolerance = 1e-3;
constexpr double kNanosecondsToSeconds = 1e-9;

using dataset_detail::at;
using dataset_detail::isDirectory;
using dataset_detail::isFile;
using dataset_detail::join;
using dataset_detail::parseDouble;
using dataset_detail::setError;

// Parses a non-negative integer of nanoseconds (digits only).
bool parseNanoseconds(const std::string& text, int64_t* value) {
  if (text.empty() || text.size() > 19) return false;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *value);
  return ec == std::errc() && ptr == end && *value >= 0;
}


// ---------------------------------------------------------------------------------------------
// sensor.yaml

// A parsed sensor.yaml with its path and the number of lines dropped before parsing, so that
// messages can name the line in the file on disk.
struct SensorYaml {
  std::string path;
  int dropped_lines = 0;
  YAML::Node root;

  // "<path>:<line>: " for a node with a position, else "<path>: ".
  std::string where(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    if (mark.is_null()) return path + ": ";
    return at(path, static_cast<size_t>(mark.line + 1 + dropped_lines));
  }

  // Binds *node to the top-level field `key` (reset(), not operator=, which would overwrite the
  // node *node already refers to), or returns false with "<path>: field '<key>' is missing".
  bool field(const std::string& key, YAML::Node* node, std::string* error) const {
    const YAML::Node found = root[key];  // invalid (not just undefined) when absent
    if (!found || found.IsNull()) {
      return setError(error, path + ": field '" + key + "' is missing or empty");
    }
    node->reset(found);
    return true;
  }
};

bool loadSensorYaml(const std::string& path, SensorYaml* yaml, std::string* error) {
  if (!isFile(path)) return setError(error, path + ": camera calibration file is missing");
  std::ifstream in(path, std::ios::binary);
  if (!in) return setError(error, path + ": cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  yaml->path = path;
  yaml->dropped_lines = 0;
  // OpenCV's FileStorage writes "%YAML:1.0", which is not a valid YAML directive.
  if (text.rfind("%YAML:", 0) == 0) {
    const size_t end_of_line = text.find('\n');
    text = end_of_line == std::string::npos ? std::string() : text.substr(end_of_line + 1);
    yaml->dropped_lines = 1;
  }
  try {
    yaml->root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    const std::string prefix =
        e.mark.is_null() ? path + ": "
                         : at(path, static_cast<size_t>(e.mark.line + 1 + yaml->dropped_lines));
    return setError(error, prefix + "YAML parse error: " + e.msg);
  }
  if (!yaml->root.IsMap()) return setError(error, path + ": expected a map of fields");
  return true;
}

// Reads a sequence of finite numbers; `name` is used in messages.
bool readNumbers(const SensorYaml& yaml, const YAML::Node& node, const std::string& name,
                 std::vector<double>* values, std::string* error) {
  if (!node.IsSequence()) {
    return setError(error, yaml.where(node) + name + ": expected a [list] of numbers");
  }
  values->clear();
  for (const YAML::Node& item : node) {
    double value = 0.0;
    if (!item.IsScalar() || !parseDouble(item.Scalar(), &value)) {
      const std::string text = item.IsScalar() ? item.Scalar() : std::string("(not a scalar)");
      return setError(error, yaml.where(item) + name + ": '" + text + "' is not a finite number");
    }
    values->push_back(value);
  }
  return true;
}

bool readNumbers(const SensorYaml& yaml, const YAML::Node& node, const std::string& name,
                 size_t expected, std::vector<double>* values, std::string* error) {
  if (!readNumbers(yaml, node, name, values, error)) return false;
  if (values->size() != expected) {
    return setError(error, yaml.where(node) + name + ": expected " + std::to_string(expected) +
                               " numbers, got " + std::to_string(values->size()));
  }
  return true;
}

bool readScalarField(const SensorYaml& yaml, const std::string& key, YAML::Node* node,
                     std::string* value, std::string* error) {
  if (!yaml.field(key, node, error)) return false;
  if (!node->IsScalar()) return setError(error, yaml.where(*node) + key + ": expected a scalar");
  *value = node->Scalar();
  return true;
}

bool readTransform(const SensorYaml& yaml, Transformationd* T_B_S, std::string* error) {
  YAML::Node node;
  if (!yaml.field("T_BS", &node, error)) return false;
  if (!node.IsMap()) return setError(error, yaml.where(node) + "T_BS: expected rows, cols, data");
  for (const char* dimension : {"rows", "cols"}) {
    const YAML::Node n = node[dimension];
    if (n && !(n.IsScalar() && n.Scalar() == "4")) {
      return setError(error, yaml.where(n) + "T_BS." + dimension + " must be 4");
    }
  }
  const YAML::Node data = node["data"];
  if (!data) return setError(error, yaml.where(node) + "T_BS: field 'data' is missing");
  std::vector<double> values;
  if (!readNumbers(yaml, data, "T_BS.data", 16, &values, error)) return false;
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) M(r, c) = values[static_cast<size_t>(r * 4 + c)];
  }
  const std::string invalid = validateRigidTransform(M);
  if (!invalid.empty()) return setError(error, yaml.where(data) + "T_BS: " + invalid);
  *T_B_S = Transformationd::fromMatrix(M);
  return true;
}

bool readCamera(const std::string& path, EurocCameraCalibration* camera, std::string* error) {
  SensorYaml yaml;
  if (!loadSensorYaml(path, &yaml, error)) return false;
  EurocCameraCalibration out;
  if (!readTransform(yaml, &out.T_B_S, error)) return false;

  YAML::Node node;
  std::vector<double> values;
  if (!yaml.field("resolution", &node, error)) return false;
  if (!readNumbers(yaml, node, "resolution", 2, &values, error)) return false;
  for (const double v : values) {
    if (!(v >= 1 && v <= 1e5) || v != std::floor(v)) {
      return setError(
          error, yaml.where(node) + "resolution: expected [width, height] as positive integers");
    }
  }
  out.intrinsics.width = static_cast<int>(values[0]);
  out.intrinsics.height = static_cast<int>(values[1]);

  std::string text;
  if (!readScalarField(yaml, "camera_model", &node, &text, error)) return false;
  if (text != "pinhole") {
    return setError(error, yaml.where(node) + "camera_model must be 'pinhole', got '" + text + "'");
  }

  if (!yaml.field("intrinsics", &node, error)) return false;
  if (!readNumbers(yaml, node, "intrinsics", 4, &values, error)) return false;
  out.intrinsics.fx = values[0];
  out.intrinsics.fy = values[1];
  out.intrinsics.cx = values[2];
  out.intrinsics.cy = values[3];
  const std::string invalid = validate(out.intrinsics);
  if (!invalid.empty()) return setError(error, yaml.where(node) + "intrinsics: " + invalid);

  if (!readScalarField(yaml, "distortion_model", &node, &out.distortion_model, error)) {
    return false;
  }
  if (out.distortion_model == "radtan") out.distortion_model = kRadTan;
  if (out.distortion_model != kRadTan && out.distortion_model != kEquidistant) {
    return setError(error, yaml.where(node) + "distortion_model '" + out.distortion_model +
                               "' is not supported (radial-tangential or equidistant)");
  }
  if (!yaml.field("distortion_coefficients", &node, error)) return false;
  if (!readNumbers(yaml, node, "distortion_coefficients", &out.distortion_coefficients, error)) {
    return false;
  }
  const size_t count = out.distortion_coefficients.size();
  if (out.distortion_model == kRadTan && count != 4 && count != 5) {
    return setError(error, yaml.where(node) +
                               "distortion_coefficients: radial-tangential needs 4 (k1 k2 p1 p2) "
                               "or 5 (k1 k2 p1 p2 k3) numbers, got " +
                               std::to_string(count));
  }
  if (out.distortion_model == kEquidistant && count != 4) {
    return setError(error, yaml.where(node) +
                               "distortion_coefficients: equidistant needs 4 numbers (k1 k2 k3 "
                               "k4), got " +
                               std::to_string(count));
  }

  if (!yaml.field("rate_hz", &node, error)) return false;
  if (!node.IsScalar() || !parseDouble(node.Scalar(), &out.rate_hz) || !(out.rate_hz > 0)) {
    return setError(error, yaml.where(node) + "rate_hz must be a number > 0, got '" +
                               (node.IsScalar() ? node.Scalar() : std::string("?")) + "'");
  }
  *camera = std::move(out);
  return true;
}

// ---------------------------------------------------------------------------------------------
// data.csv files

struct ImageEntry {
  int64_t timestamp_ns = 0;
  std::string filename;
};

// Reads "timestamp [ns],filename" lines; '#' lines and empty lines are skipped.
bool readImageList(const std::string& path, std::vector<ImageEntry>* entries, std::string* error) {
  if (!isFile(path)) return setError(error, path + ": image list is missing");
  std::ifstream in(path);
  if (!in) return setError(error, path + ": cannot open file");
  entries->clear();
  std::string line;
  size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string text = trimBlanks(line);
    if (text.empty() || text[0] == '#') continue;
    const std::vector<std::string> fields = splitCommas(text);
    if (fields.size() != 2 || fields[1].empty()) {
      return setError(
          error, at(path, line_number) + "expected 'timestamp [ns],filename', got '" + text + "'");
    }
    ImageEntry entry;
    if (!parseNanoseconds(fields[0], &entry.timestamp_ns)) {
      return setError(error, at(path, line_number) + "timestamp '" + fields[0] +
                                 "' is not a non-negative integer of nanoseconds");
    }
    if (!entries->empty() && entry.timestamp_ns <= entries->back().timestamp_ns) {
      return setError(error, at(path, line_number) + "timestamp " +
                                 std::to_string(entry.timestamp_ns) +
                                 " does not increase (previous " +
                                 std::to_string(entries->back().timestamp_ns) + ")");
    }
    entry.filename = fields[1];
    entries->push_back(std::move(entry));
  }
  if (in.bad()) return setError(error, path + ": read error");
  return true;
}

// Reads the ground-truth csv: t [ns], p_RS_R x y z [m], q_RS w x y z, then any further columns.
// Times are stored in seconds relative to epoch_ns to keep double precision.
bool readGroundTruth(const std::string& path, int64_t epoch_ns, StampedTrajectory* trajectory,
                     std::string* error) {
  std::ifstream in(path);
  if (!in) return setError(error, path + ": cannot open file");
  trajectory->clear();
  std::string line;
  size_t line_number = 0;
  int64_t previous_ns = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string text = trimBlanks(line);
    if (text.empty() || text[0] == '#') continue;
    const std::vector<std::string> fields = splitCommas(text);
    if (fields.size() < 8) {
      return setError(error, at(path, line_number) +
                                 "expected at least 8 comma-separated values (t [ns], p_RS_R x y "
                                 "z, q_RS w x y z), got " +
                                 std::to_string(fields.size()));
    }
    int64_t timestamp_ns = 0;
    if (!parseNanoseconds(fields[0], &timestamp_ns)) {
      return setError(error, at(path, line_number) + "timestamp '" + fields[0] +
                                 "' is not a non-negative integer of nanoseconds");
    }
    double v[7];
    for (int k = 0; k < 7; ++k) {
      if (!parseDouble(fields[static_cast<size_t>(k + 1)], &v[k])) {
        return setError(error, at(path, line_number) + "'" + fields[static_cast<size_t>(k + 1)] +
                                   "' is not a finite number");
      }
    }
    if (!trajectory->empty() && timestamp_ns <= previous_ns) {
      return setError(error, at(path, line_number) + "timestamp " + std::to_string(timestamp_ns) +
                                 " does not increase (previous " + std::to_string(previous_ns) +
                                 ")");
    }
    const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > kQuaternionNormTolerance) {
      return setError(error, at(path, line_number) + "quaternion norm is " +
                                 std::to_string(q.norm()) + ", not 1 (within 1e-3)");
    }
    const double t_s = static_cast<double>(timestamp_ns - epoch_ns) * kNanosecondsToSeconds;
    trajectory->push_back({t_s, Transformationd(q, Eigen::Vector3d(v[0], v[1], v[2]))});
    previous_ns = timestamp_ns;
  }
  if (in.bad()) return setError(error, path + ": read error");
  if (trajectory->empty()) return setError(error, path + ": no pose in ground-truth file");
  return true;
}

}  // namespace

std::string EurocReader::Options::validate() const {
  if (!(groundtruth_max_gap_s > 0) || !std::isfinite(groundtruth_max_gap_s)) {
    return "groundtruth_max_gap_s must be > 0 and finite, got " +
           std::to_string(groundtruth_max_gap_s);
  }
  return {};
}

std::optional<EurocReader> EurocReader::open(const std::string& folder, const Options& options,
                                             std::string* error) {
  const std::string invalid_options = options.validate();
  if (!invalid_options.empty()) {
    setError(error, "EurocReader::Options: " + invalid_options);
    return std::nullopt;
  }
  if (!isDirectory(folder)) {
    setError(error, folder + ": not a readable directory");
    return std::nullopt;
  }
  EurocReader reader;
  if (isDirectory(join(folder, kMav0))) {
    reader.mav0_ = join(folder, kMav0);
  } else if (isDirectory(join(folder, "cam0")) && isDirectory(join(folder, "cam1"))) {
    reader.mav0_ = folder;
  } else {
    setError(error, folder + ": not a EuRoC folder (neither mav0/ nor cam0/ and cam1/ inside)");
    return std::nullopt;
  }
  const std::string& mav0 = reader.mav0_;

  // Calibration.
  const std::string cam0_yaml = join(join(mav0, "cam0"), kSensorFile);
  const std::string cam1_yaml = join(join(mav0, "cam1"), kSensorFile);
  if (!readCamera(cam0_yaml, &reader.cam0_, error)) return std::nullopt;
  if (!readCamera(cam1_yaml, &reader.cam1_, error)) return std::nullopt;
  const PinholeIntrinsics& in0 = reader.cam0_.intrinsics;
  const PinholeIntrinsics& in1 = reader.cam1_.intrinsics;
  if (in0.width != in1.width || in0.height != in1.height) {
    setError(error, cam1_yaml + ": resolution " + describeSize(in1.width, in1.height) +
                        " differs from cam0's " + describeSize(in0.width, in0.height));
    return std::nullopt;
  }
  if (reader.cam0_.distortion_model != reader.cam1_.distortion_model) {
    setError(error, cam1_yaml + ": distortion_model '" + reader.cam1_.distortion_model +
                        "' differs from cam0's '" + reader.cam0_.distortion_model + "'");
    return std::nullopt;
  }

  // Image lists, paired by identical timestamps.
  std::vector<ImageEntry> list0;
  std::vector<ImageEntry> list1;
  if (!readImageList(join(join(mav0, "cam0"), kImageList), &list0, error)) return std::nullopt;
  if (!readImageList(join(join(mav0, "cam1"), kImageList), &list1, error)) return std::nullopt;
  const auto relative = [](const char* camera, const ImageEntry& entry) {
    return std::string(camera) + "/" + kImageFolder + "/" + entry.filename;
  };
  size_t i0 = 0;
  size_t i1 = 0;
  while (i0 < list0.size() || i1 < list1.size()) {
    if (i1 == list1.size() ||
        (i0 < list0.size() && list0[i0].timestamp_ns < list1[i1].timestamp_ns)) {
      reader.skipped_.push_back(relative("cam0", list0[i0]) + ": no cam1 image with timestamp " +
                                std::to_string(list0[i0].timestamp_ns) + ", skipped");
      ++i0;
      continue;
    }
    if (i0 == list0.size() || list1[i1].timestamp_ns < list0[i0].timestamp_ns) {
      reader.skipped_.push_back(relative("cam1", list1[i1]) + ": no cam0 image with timestamp " +
                                std::to_string(list1[i1].timestamp_ns) + ", skipped");
      ++i1;
      continue;
    }
    const int64_t timestamp_ns = list0[i0].timestamp_ns;
    FrameFiles files;
    files.timestamp_ns = timestamp_ns;
    files.left_path = join(mav0, relative("cam0", list0[i0]));
    files.right_path = join(mav0, relative("cam1", list1[i1]));
    bool complete = true;
    for (const auto& [camera, entry, path] : {std::tuple{"cam0", &list0[i0], &files.left_path},
                                              std::tuple{"cam1", &list1[i1], &files.right_path}}) {
      if (!isFile(*path)) {
        reader.skipped_.push_back(relative(camera, *entry) + ": missing, frame " +
                                  std::to_string(timestamp_ns) + " skipped");
        complete = false;
      }
    }
    if (complete) reader.frames_.push_back(std::move(files));
    ++i0;
    ++i1;
  }
  if (reader.frames_.empty()) {
    setError(error, mav0 + ": no complete stereo pair (" + std::to_string(list0.size()) +
                        " cam0 and " + std::to_string(list1.size()) + " cam1 entries" +
                        (reader.skipped_.empty() ? std::string()
                                                 : "; first skipped: " + reader.skipped_.front()) +
                        ")");
    return std::nullopt;
  }
  if (!reader.skipped_.empty()) {
    reader.notes_.push_back(std::to_string(reader.skipped_.size()) +
                            " image entries skipped (unpaired or missing on disk), see skipped()");
  }

  // Rectification, built once.
  StereoCameraCalibration raw;
  raw.source = cam1_yaml;
  for (const auto& [in, out] : {std::pair{&reader.cam0_, &raw.left}, {&reader.cam1_, &raw.right}}) {
    out->intrinsics = in->intrinsics;
    out->distortion = in->distortion_model == kEquidistant ? DistortionModel::kEquidistant
                                                           : DistortionModel::kRadTan;
    out->distortion_coefficients = in->distortion_coefficients;
    out->T_B_C = in->T_B_S;
  }
  raw.T_R_L = reader.cam1_.T_B_S.inverse() * reader.cam0_.T_B_S;
  reader.rectifier_ = StereoRectifier::create(raw, error);
  if (reader.rectifier_ == nullptr) return std::nullopt;
  reader.calibration_ = reader.rectifier_->rectified();

  // Ground truth.
  const std::string groundtruth_path = join(mav0, kGroundTruth);
  if (isFile(groundtruth_path)) {
    StampedTrajectory trajectory;
    const int64_t epoch_ns = reader.frames_.front().timestamp_ns;
    if (!readGroundTruth(groundtruth_path, epoch_ns, &trajectory, error)) return std::nullopt;
    reader.has_groundtruth_ = true;
    size_t without = 0;
    for (FrameFiles& files : reader.frames_) {
      const double t_s = static_cast<double>(files.timestamp_ns - epoch_ns) * kNanosecondsToSeconds;
      const std::optional<Transformationd> T_W_B =
          interpolatePose(trajectory, t_s, options.groundtruth_max_gap_s);
      if (T_W_B) {
        files.T_G_L = *T_W_B * reader.calibration_.T_B_L;
      } else {
        ++without;
      }
    }
    if (without > 0) {
      std::ostringstream os;
      os << without << " of " << reader.frames_.size() << " frames have no ground truth "
         << "(outside " << kMav0 << "/" << kGroundTruth << "'s time range or in a gap > "
         << options.groundtruth_max_gap_s << " s)";
      reader.notes_.push_back(os.str());
    }
  } else {
    reader.notes_.push_back(std::string("no ground truth: ") + kMav0 + "/" + kGroundTruth +
                            " absent");
  }
  return reader;
}

bool EurocReader::read(size_t i, EurocStereoFrame* frame, std::string* error) const {
  if (i >= frames_.size()) {
    return setError(error, mav0_ + ": frame " + std::to_string(i) + " out of range (size " +
                               std::to_string(frames_.size()) + ")");
  }
  const FrameFiles& files = frames_[i];
  const int width = cam0_.intrinsics.width;
  const int height = cam0_.intrinsics.height;

  EurocStereoFrame out;
  out.timestamp_ns = files.timestamp_ns;
  out.T_G_L = files.T_G_L;
  const auto load = [&](const std::string& path, bool right, GrayImage* image) {
    cv::Mat raw;
    if (!readGrayImage(path, &raw, error)) return false;
    if (!checkImageSize(path, raw, width, height, "sensor.yaml's resolution", error)) {
      return false;
    }
    *image = GrayImage(width, height);
    cv::Mat rectified(height, width, CV_8UC1, image->data.data());
    rectifier_->rectifyImage(right, raw, &rectified);
    return true;
  };
  if (!load(files.left_path, false, &out.left)) return false;
  if (!load(files.right_path, true, &out.right)) return false;
  *frame = std::move(out);
  return true;
}

}  // namespace cblox
