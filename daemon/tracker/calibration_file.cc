#include "daemon/tracker/calibration_file.h"

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <vector>

#include "daemon/common/yaml_config.h"
#include "drivers/dataset/text_matrix.h"

namespace cblox {
namespace {

std::vector<double> readNumberList(const YAML::Node& node, const std::string& key,
                                   size_t expected) {
  std::vector<double> values;
  bool ok = node.IsSequence() && (expected == 0 || node.size() == expected);
  for (size_t i = 0; ok && i < node.size(); ++i) {
    try {
      values.push_back(node[i].as<double>());
    } catch (const YAML::Exception&) {
      ok = false;
    }
    ok = ok && std::isfinite(values.back());
  }
  if (!ok) {
    throw ConfigError(key + ": expected a list of " +
                      (expected > 0 ? std::to_string(expected) + " " : std::string()) +
                      "finite numbers, got '" + YAML::Dump(node) + "'");
  }
  return values;
}

Transformationd toRigidTransform(const Eigen::Matrix4d& M, const std::string& key) {
  if (const std::string e = validateRigidTransform(M); !e.empty()) {
    throw ConfigError(key + ": " + e);
  }
  return Transformationd::fromMatrix(M);
}

// EuRoC: {rows: 4, cols: 4, data: [16 numbers]}.
Transformationd readEurocTransform(const YAML::Node& node, const std::string& key) {
  requireKnownKeys(node, key, {"rows", "cols", "data"});
  if (!node.IsMap() || !node["data"]) throw ConfigError(key + ": expected rows, cols and data");
  for (const char* dimension : {"rows", "cols"}) {
    if (node[dimension] && node[dimension].as<std::string>() != "4") {
      throw ConfigError(key + "." + dimension + ": must be 4");
    }
  }
  const std::vector<double> values = readNumberList(node["data"], key + ".data", 16);
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) M(r, c) = values[static_cast<size_t>(4 * r + c)];
  }
  return toRigidTransform(M, key);
}

// Kalibr: four rows of four numbers.
Transformationd readKalibrTransform(const YAML::Node& node, const std::string& key) {
  if (!node.IsSequence() || node.size() != 4) {
    throw ConfigError(key + ": expected 4 rows of 4 numbers");
  }
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r) {
    const std::vector<double> row =
        readNumberList(node[static_cast<size_t>(r)], key + "[" + std::to_string(r) + "]", 4);
    for (int c = 0; c < 4; ++c) M(r, c) = row[static_cast<size_t>(c)];
  }
  return toRigidTransform(M, key);
}

struct CameraEntry {
  PinholeIntrinsics intrinsics;
  std::optional<Transformationd> T_B_C;  // from T_BS, or T_cam_imu inverted
  std::optional<Transformationd> T_C1_C0;
};

CameraEntry readCamera(const YAML::Node& node, const std::string& key) {
  if (isAbsent(node) || !node.IsMap()) throw ConfigError(key + ": missing (a map of fields)");
  requireKnownKeys(
      node, key,
      {"camera_model", "intrinsics", "resolution", "distortion_model", "distortion_coeffs",
       "distortion_coefficients", "T_BS", "T_cam_imu", "T_cn_cnm1", "rostopic", "sensor_type",
       "comment", "rate_hz", "cam_overlaps", "timeshift_cam_imu"});
  CameraEntry camera;
  if (node["camera_model"] && node["camera_model"].as<std::string>() != "pinhole") {
    throw ConfigError(key + ".camera_model: only 'pinhole' is supported, got '" +
                      node["camera_model"].as<std::string>() + "'");
  }
  if (!node["intrinsics"]) throw ConfigError(key + ".intrinsics: missing ([fu, fv, pu, pv])");
  if (!node["resolution"]) throw ConfigError(key + ".resolution: missing ([width, height])");
  const std::vector<double> k = readNumberList(node["intrinsics"], key + ".intrinsics", 4);
  const std::vector<double> size = readNumberList(node["resolution"], key + ".resolution", 2);
  for (const double v : size) {
    if (!(v >= 1.0 && v <= 16384.0) || v != std::floor(v)) {
      throw ConfigError(key + ".resolution: expected [width, height] as positive integers");
    }
  }
  camera.intrinsics = PinholeIntrinsics{
      k[0], k[1], k[2], k[3], static_cast<int>(size[0]), static_cast<int>(size[1])};
  if (const std::string e = validate(camera.intrinsics); !e.empty()) {
    throw ConfigError(key + ".intrinsics: " + e);
  }
  for (const char* field : {"distortion_coeffs", "distortion_coefficients"}) {
    if (!node[field]) continue;
    for (const double c : readNumberList(node[field], key + "." + field, 0)) {
      if (c != 0.0) {
        throw ConfigError(key + "." + field +
                          ": must be all 0 (the tracker takes rectified, undistorted images; "
                          "rectify in the capture)");
      }
    }
  }
  if (node["T_BS"]) camera.T_B_C = readEurocTransform(node["T_BS"], key + ".T_BS");
  if (node["T_cam_imu"]) {
    if (camera.T_B_C) throw ConfigError(key + ": give T_BS or T_cam_imu, not both");
    camera.T_B_C = readKalibrTransform(node["T_cam_imu"], key + ".T_cam_imu").inverse();
  }
  if (node["T_cn_cnm1"])
    camera.T_C1_C0 = readKalibrTransform(node["T_cn_cnm1"], key + ".T_cn_cnm1");
  return camera;
}

bool sameIntrinsics(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  constexpr double kTolerance = 1e-6;
  return a.width == b.width && a.height == b.height && std::abs(a.fx - b.fx) <= kTolerance &&
         std::abs(a.fy - b.fy) <= kTolerance && std::abs(a.cx - b.cx) <= kTolerance &&
         std::abs(a.cy - b.cy) <= kTolerance;
}

RectifiedStereoCalibration parseCalibrationTree(const YAML::Node& root, const std::string& where,
                                                bool stereo) {
  if (isAbsent(root) || !root.IsMap()) throw ConfigError(where + ": expected cam0 (and cam1)");
  requireKnownKeys(root, where, {"cam0", "cam1"});
  const CameraEntry left = readCamera(root["cam0"], where + ".cam0");
  RectifiedStereoCalibration calibration;
  calibration.intrinsics = left.intrinsics;
  calibration.T_B_L = left.T_B_C.value_or(Transformationd::Identity());
  if (!stereo) return calibration;

  const std::string key = where + ".cam1";
  const CameraEntry right = readCamera(root["cam1"], key);
  if (!sameIntrinsics(left.intrinsics, right.intrinsics)) {
    throw ConfigError(key + ": intrinsics and resolution must equal cam0's (a rectified pair)");
  }
  Transformationd T_L_R;
  if (right.T_C1_C0) {
    T_L_R = right.T_C1_C0->inverse();
  } else if (left.T_B_C && right.T_B_C) {
    T_L_R = left.T_B_C->inverse() * *right.T_B_C;
  } else {
    throw ConfigError(key + ": needs T_cn_cnm1, or T_BS (or T_cam_imu) on both cameras");
  }
  const Eigen::Vector3d& t = T_L_R.translation();
  constexpr double kTolerance = 1e-6;
  if (T_L_R.rotation().angularDistance(Eigen::Quaterniond::Identity()) > kTolerance ||
      std::abs(t.y()) > kTolerance || std::abs(t.z()) > kTolerance || !(t.x() > 0.0)) {
    std::ostringstream os;
    os << key << ": the right camera must sit at (+baseline, 0, 0) in the left one without "
       << "rotation (a rectified pair); it is at (" << t.x() << ", " << t.y() << ", " << t.z()
       << ") m, rotated by " << T_L_R.rotation().angularDistance(Eigen::Quaterniond::Identity())
       << " rad";
    throw ConfigError(os.str());
  }
  calibration.baseline_m = t.x();
  return calibration;
}

}  // namespace

RectifiedStereoCalibration parseCalibration(const YAML::Node& root, const std::string& where,
                                            bool stereo) {
  try {
    return parseCalibrationTree(root, where, stereo);
  } catch (const YAML::Exception& e) {
    throw ConfigError(where + ": " + e.what());
  }
}

RectifiedStereoCalibration loadCalibrationFile(const std::string& path, bool stereo) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open calibration file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  if (text.rfind("%YAML:", 0) == 0) {
    const size_t end = text.find('\n');
    text.replace(0, end == std::string::npos ? text.size() : end, 1, '#');  // keeps lines
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": " + e.what());
  }
  return parseCalibration(root, path, stereo);
}

}  // namespace cblox
