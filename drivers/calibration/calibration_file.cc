#include "drivers/calibration/calibration_file.h"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <vector>

#include "core/io/text_matrix.h"
#include "drivers/calibration/opencv_storage.h"

namespace cblox {
namespace {

[[noreturn]] void fail(const std::string& message) { throw CalibrationError(message); }

bool absent(const YAML::Node& node) { return !node.IsDefined() || node.IsNull(); }

void onlyKeys(const YAML::Node& node, const std::string& where,
              std::initializer_list<const char*> known) {
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    bool found = false;
    for (const char* k : known) found = found || key == k;
    if (!found) fail(where + "." + key + ": unknown key");
  }
}

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
    fail(key + ": expected a list of " +
         (expected > 0 ? std::to_string(expected) + " " : std::string()) +
         "finite numbers, got '" + YAML::Dump(node) + "'");
  }
  return values;
}

Transformationd toRigidTransform(const Eigen::Matrix4d& M, const std::string& key) {
  if (const std::string e = validateRigidTransform(M); !e.empty()) fail(key + ": " + e);
  return Transformationd::fromMatrix(M);
}

// EuRoC: {rows: 4, cols: 4, data: [16 numbers]}.
Transformationd readEurocTransform(const YAML::Node& node, const std::string& key) {
  if (!node.IsMap() || !node["data"]) fail(key + ": expected rows, cols and data");
  onlyKeys(node, key, {"rows", "cols", "data"});
  for (const char* dimension : {"rows", "cols"}) {
    if (node[dimension] && node[dimension].as<std::string>() != "4") {
      fail(key + "." + dimension + ": must be 4");
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
  if (!node.IsSequence() || node.size() != 4) fail(key + ": expected 4 rows of 4 numbers");
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r) {
    const std::vector<double> row =
        readNumberList(node[static_cast<size_t>(r)], key + "[" + std::to_string(r) + "]", 4);
    for (int c = 0; c < 4; ++c) M(r, c) = row[static_cast<size_t>(c)];
  }
  return toRigidTransform(M, key);
}

DistortionModel parseDistortionModel(const std::string& name, const std::string& key) {
  if (name == "radtan" || name == "radial-tangential" || name == "plumb_bob") {
    return DistortionModel::kRadTan;
  }
  if (name == "equidistant" || name == "fisheye") return DistortionModel::kEquidistant;
  if (name == "none") return DistortionModel::kNone;
  fail(key + ": unsupported distortion model '" + name +
       "' (radtan, radial-tangential, equidistant or none)");
}

struct CamchainEntry {
  CameraCalibration camera;
  std::optional<Transformationd> T_C1_C0;
};

CamchainEntry readCamchainCamera(const YAML::Node& node, const std::string& key) {
  if (absent(node) || !node.IsMap()) fail(key + ": missing (a map of fields)");
  onlyKeys(node, key,
           {"camera_model", "intrinsics", "resolution", "distortion_model", "distortion_coeffs",
            "distortion_coefficients", "T_BS", "T_cam_imu", "T_cn_cnm1", "rostopic",
            "sensor_type", "comment", "rate_hz", "cam_overlaps", "timeshift_cam_imu"});
  CamchainEntry entry;
  CameraCalibration& camera = entry.camera;
  if (node["camera_model"] && node["camera_model"].as<std::string>() != "pinhole") {
    fail(key + ".camera_model: only 'pinhole' is supported, got '" +
         node["camera_model"].as<std::string>() + "'");
  }
  if (!node["intrinsics"]) fail(key + ".intrinsics: missing ([fu, fv, pu, pv])");
  if (!node["resolution"]) fail(key + ".resolution: missing ([width, height])");
  const std::vector<double> k = readNumberList(node["intrinsics"], key + ".intrinsics", 4);
  const std::vector<double> size = readNumberList(node["resolution"], key + ".resolution", 2);
  for (const double v : size) {
    if (!(v >= 1.0 && v <= 16384.0) || v != std::floor(v)) {
      fail(key + ".resolution: expected [width, height] as positive integers");
    }
  }
  camera.intrinsics = PinholeIntrinsics{k[0], k[1], k[2], k[3], static_cast<int>(size[0]),
                                        static_cast<int>(size[1])};
  if (const std::string e = validate(camera.intrinsics); !e.empty()) {
    fail(key + ".intrinsics: " + e);
  }
  camera.distortion = DistortionModel::kRadTan;
  if (node["distortion_model"]) {
    camera.distortion = parseDistortionModel(node["distortion_model"].as<std::string>(),
                                             key + ".distortion_model");
  }
  for (const char* field : {"distortion_coeffs", "distortion_coefficients"}) {
    if (!node[field]) continue;
    if (!camera.distortion_key.empty()) fail(key + ": give " + field + " only once");
    camera.distortion_key = key + "." + field;
    camera.distortion_coefficients = readNumberList(node[field], camera.distortion_key, 0);
  }
  if (camera.distortion_key.empty()) camera.distortion_key = key + ".distortion_coeffs";
  if (camera.distortion_coefficients.empty()) camera.distortion = DistortionModel::kNone;
  if (const std::string e = validate(camera); !e.empty()) fail(camera.distortion_key + ": " + e);
  if (node["T_BS"]) camera.T_B_C = readEurocTransform(node["T_BS"], key + ".T_BS");
  if (node["T_cam_imu"]) {
    if (camera.T_B_C) fail(key + ": give T_BS or T_cam_imu, not both");
    camera.T_B_C = readKalibrTransform(node["T_cam_imu"], key + ".T_cam_imu").inverse();
  }
  if (node["T_cn_cnm1"]) {
    entry.T_C1_C0 = readKalibrTransform(node["T_cn_cnm1"], key + ".T_cn_cnm1");
  }
  return entry;
}

// ---------------------------------------------------------------------------------------------
// OpenCV FileStorage (read by readOpenCvStorage, never by OpenCV's parsers)

// The first of `names` present, as a matrix (`*found` its name); nullopt with `*found` empty
// when none is present.
std::optional<OpenCvMatrix> readMatrix(const YAML::Node& root, const std::string& path,
                                       std::initializer_list<const char*> names,
                                       std::string* found) {
  for (const char* name : names) {
    const YAML::Node node = root[name];
    if (!node) continue;
    OpenCvMatrix m;
    if (const std::string e = readOpenCvMatrix(node, &m); !e.empty()) {
      fail(path + "." + name + ": " + e);
    }
    *found = name;
    return m;
  }
  found->clear();
  return std::nullopt;
}

// As readMatrix, one of `names` required, finite, and rows x cols unless `rows` is 0.
OpenCvMatrix requireMatrix(const YAML::Node& root, const std::string& path,
                           std::initializer_list<const char*> names, int rows, int cols) {
  std::string found;
  const std::optional<OpenCvMatrix> m = readMatrix(root, path, names, &found);
  std::string all;
  for (const char* name : names) all += (all.empty() ? "" : " or ") + std::string(name);
  if (!m) fail(path + ": " + all + " is missing");
  if (rows > 0 && (m->rows != rows || m->cols != cols)) {
    fail(path + "." + found + ": expected a " + std::to_string(rows) + "x" + std::to_string(cols) +
         " matrix, got " + std::to_string(m->rows) + "x" + std::to_string(m->cols));
  }
  for (const double v : m->values) {
    if (!std::isfinite(v)) fail(path + "." + found + ": not finite");
  }
  return *m;
}

// A whole number in 1..16384 (an image side), else nullopt.
std::optional<int> imageSide(std::optional<double> v) {
  if (!v || !(*v >= 1 && *v <= 16384) || std::floor(*v) != *v) return std::nullopt;
  return static_cast<int>(*v);
}

std::optional<int> imageSide(const YAML::Node& node) {
  return imageSide(node.IsScalar() ? parseOpenCvNumber(node.Scalar()) : std::nullopt);
}

// image_width and image_height, or imageSize / image_size / size as [w, h] or a 2-element
// matrix. nullopt when absent or not two image sides.
std::optional<std::pair<int, int>> readImageSize(const YAML::Node& root) {
  const YAML::Node w = root["image_width"], h = root["image_height"];
  if (w && h) {
    const std::optional<int> width = imageSide(w), height = imageSide(h);
    if (width && height) return std::make_pair(*width, *height);
    return std::nullopt;
  }
  for (const char* name : {"imageSize", "image_size", "size"}) {
    const YAML::Node node = root[name];
    if (!node) continue;
    if (node.IsSequence() && node.size() == 2) {
      const std::optional<int> width = imageSide(node[0]), height = imageSide(node[1]);
      if (width && height) return std::make_pair(*width, *height);
      return std::nullopt;
    }
    OpenCvMatrix m;
    if (readOpenCvMatrix(node, &m).empty() && m.values.size() == 2) {
      const std::optional<int> width = imageSide(m.values[0]), height = imageSide(m.values[1]);
      if (width && height) return std::make_pair(*width, *height);
    }
    return std::nullopt;
  }
  return std::nullopt;
}

CameraCalibration openCvCamera(const OpenCvMatrix& K, const std::optional<OpenCvMatrix>& D,
                               std::pair<int, int> size, DistortionModel model,
                               const std::string& where) {
  CameraCalibration camera;
  try {
    const Eigen::Matrix3d k =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(K.values.data());
    camera.intrinsics = PinholeCamera::fromK(k, size.first, size.second);
  } catch (const std::invalid_argument& e) {
    fail(where + ": " + e.what());
  }
  camera.distortion = model;
  if (D) camera.distortion_coefficients = D->values;
  camera.distortion_key = where;
  if (camera.distortion_coefficients.empty()) camera.distortion = DistortionModel::kNone;
  if (const std::string e = validate(camera); !e.empty()) fail(where + ": " + e);
  return camera;
}

YAML::Node openStorage(const std::string& path) {
  std::string error;
  std::optional<YAML::Node> root = readOpenCvStorage(path, &error);
  if (!root) fail(error);
  return *root;
}

StereoCameraCalibration readOpenCv(YAML::Node root, const std::string& path, bool stereo) {
  const std::optional<std::pair<int, int>> size = readImageSize(root);
  if (!size) {
    fail(path + ": image_width and image_height (or imageSize: [w, h]) missing or invalid");
  }
  DistortionModel model = DistortionModel::kRadTan;
  if (const YAML::Node name = root["distortion_model"]) {
    if (!name.IsScalar()) fail(path + ".distortion_model: expected a name");
    model = parseDistortionModel(name.Scalar(), path + ".distortion_model");
  }
  StereoCameraCalibration calibration;
  calibration.source = path;
  std::string found;
  const OpenCvMatrix K1 = requireMatrix(root, path, {"M1", "K1", "cameraMatrix1"}, 3, 3);
  const std::optional<OpenCvMatrix> D1 = readMatrix(root, path, {"D1", "distCoeffs1"}, &found);
  calibration.left = openCvCamera(K1, D1, *size, model, path + ".D1");
  if (!stereo) return calibration;
  const OpenCvMatrix K2 = requireMatrix(root, path, {"M2", "K2", "cameraMatrix2"}, 3, 3);
  const std::optional<OpenCvMatrix> D2 = readMatrix(root, path, {"D2", "distCoeffs2"}, &found);
  calibration.right = openCvCamera(K2, D2, *size, model, path + ".D2");

  std::string extrinsics_path = path;
  if (!root["R"] && !root["T"]) {
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    extrinsics_path.clear();
    for (const char* name : {"extrinsics.yml", "extrinsics.yaml", "extrinsics.xml"}) {
      if (std::filesystem::exists(folder / name)) {
        extrinsics_path = (folder / name).string();
        break;
      }
    }
    if (extrinsics_path.empty()) {
      fail(path + ": R and T (right camera from left) missing, and no extrinsics.yml beside it");
    }
    root = openStorage(extrinsics_path);
  }
  const OpenCvMatrix R = requireMatrix(root, extrinsics_path, {"R"}, 3, 3);
  const OpenCvMatrix T = requireMatrix(root, extrinsics_path, {"T"}, 0, 0);
  if (T.values.size() != 3) fail(extrinsics_path + ".T: expected 3 numbers");
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) M(r, c) = R.values[static_cast<size_t>(3 * r + c)];
    M(r, 3) = T.values[static_cast<size_t>(r)];
  }
  calibration.T_R_L = toRigidTransform(M, extrinsics_path + ".R");
  return calibration;
}

// readOpenCv, with a yaml-cpp exception on a tree of unexpected shape as a CalibrationError.
StereoCameraCalibration readOpenCvChecked(const YAML::Node& root, const std::string& path,
                                          bool stereo) {
  try {
    return readOpenCv(root, path, stereo);
  } catch (const YAML::Exception& e) {
    fail(path + ": cannot read as OpenCV YAML/XML: " + e.what());
  }
}

}  // namespace

StereoCameraCalibration parseCamchain(const YAML::Node& root, const std::string& where,
                                      bool stereo) {
  try {
    if (absent(root) || !root.IsMap()) fail(where + ": expected cam0 (and cam1)");
    onlyKeys(root, where, {"cam0", "cam1"});
    StereoCameraCalibration calibration;
    calibration.source = where;
    const CamchainEntry left = readCamchainCamera(root["cam0"], where + ".cam0");
    calibration.left = left.camera;
    if (!stereo) return calibration;
    const std::string key = where + ".cam1";
    const CamchainEntry right = readCamchainCamera(root["cam1"], key);
    calibration.right = right.camera;
    if (right.T_C1_C0) {
      calibration.T_R_L = *right.T_C1_C0;
    } else if (left.camera.T_B_C && right.camera.T_B_C) {
      calibration.T_R_L = right.camera.T_B_C->inverse() * *left.camera.T_B_C;
    } else {
      fail(key + ": needs T_cn_cnm1, or T_BS (or T_cam_imu) on both cameras");
    }
    return calibration;
  } catch (const YAML::Exception& e) {
    fail(where + ": " + e.what());
  }
}

StereoCameraCalibration loadStereoCalibration(const std::string& path, bool stereo) {
  const YAML::Node root = openStorage(path);
  if (root["cam0"]) return parseCamchain(root, path, stereo);
  return readOpenCvChecked(root, path, stereo);
}

}  // namespace cblox
