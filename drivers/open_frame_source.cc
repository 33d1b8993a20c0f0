#include "drivers/open_frame_source.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include "core/io/ply_io.h"
#include "core/io/text_fields.h"
#include "drivers/calibration/calibration_file.h"
#include "drivers/calibration/stereo_rectifier.h"
#include "drivers/libcamera/libcamera_source.h"
#include "drivers/dataset/dataset_sources.h"
#include "drivers/sim/builtin_scenes.h"
#include "drivers/sim/scene_mesh_loader.h"
#include "drivers/v4l2/v4l2_source.h"

namespace cblox {
namespace {

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

bool isBuiltin(const std::string& name) {
  const std::vector<std::string> names = builtinSceneNames();
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// An orbit around the mesh: radius 0.75 of the larger horizontal half-size plus a margin,
/// at 60 % of the height, looking at the bounding-box centre.
StampedTrajectory orbitAroundMesh(const Mesh& mesh, const MotionProfile& motion, int laps) {
  Eigen::AlignedBox3d bounds;
  for (const Eigen::Vector3f& v : mesh.vertices) bounds.extend(v.cast<double>());
  const Eigen::Vector3d centre = bounds.center();
  const Eigen::Vector3d size = bounds.sizes();
  const double radius = 0.5 * std::max(size.x(), size.y()) + 0.5 * std::max(1.0, size.z());
  Eigen::Vector3d orbit_centre = centre;
  orbit_centre.z() = bounds.min().z() + 0.6 * size.z() + 0.5;
  return followPath(orbitWaypoints(orbit_centre, radius), true, laps, motion, centre);
}

std::unique_ptr<FrameSource> openSim(const std::string& what, const SourceConfig& options,
                                     std::string* error, std::vector<std::string>* warnings) {
  // A built-in scene is generated once here, for its mesh and its paths.
  std::optional<BuiltinScene> builtin;
  if (isBuiltin(what)) builtin = makeBuiltinScene(what);
  std::vector<std::string> mesh_warnings;
  std::shared_ptr<const Mesh> mesh = builtin
                                         ? std::make_shared<const Mesh>(builtin->mesh)
                                         : loadSimSceneMesh("sim:" + what, error, &mesh_warnings);
  if (mesh == nullptr) return nullptr;
  SimSourceConfig config = options.sim;
  config.max_frames = options.max_frames > 0 ? options.max_frames : config.max_frames;
  StampedTrajectory trajectory;
  std::string trajectory_name = options.trajectory;
  try {
    const bool is_file = std::filesystem::exists(options.trajectory) ||
                         options.trajectory.find('/') != std::string::npos ||
                         options.trajectory.ends_with(".txt");
    if (is_file) {
      auto read = readTumTrajectory(options.trajectory, error);
      if (!read.has_value()) return nullptr;
      trajectory = std::move(*read);
      trajectory_name = std::filesystem::path(options.trajectory).filename().string();
    } else if (builtin) {
      const BuiltinScene& scene = *builtin;
      trajectory = makeSceneTrajectory(scene, parseTrajectoryKind(options.trajectory),
                                       std::max(config.rate_hz, 50.0), options.laps);
      if (!options.keep_rig_range) {
        config.renderer.rig.depth_max_m = scene.depth_max_m;
        config.renderer.texture.base_wavelength_m = scene.texture_wavelength_m;
      }
    } else if (options.trajectory == "orbit") {
      trajectory = orbitAroundMesh(*mesh, MotionProfile{}, options.laps);
    } else {
      setError(error, "sim:" + what + ": a mesh file needs --trajectory orbit or a TUM file, got '" +
                          options.trajectory + "'");
      return nullptr;
    }
  } catch (const std::invalid_argument& e) {
    setError(error, e.what());
    return nullptr;
  }
  std::string build_error;
  std::shared_ptr<const TriangleMeshRaycaster> scene =
      TriangleMeshRaycaster::create(*mesh, &build_error);
  if (scene == nullptr) {
    setError(error, "sim:" + what + ": " + build_error);
    return nullptr;
  }
  try {
    auto source = std::make_unique<SimSource>("sim:" + what + "/" + trajectory_name,
                                              std::move(scene), std::move(trajectory), config);
    for (const std::string& warning : mesh_warnings) source->addNote("warning: " + warning);
    if (warnings != nullptr) {
      warnings->insert(warnings->end(), mesh_warnings.begin(), mesh_warnings.end());
    }
    return source;
  } catch (const std::invalid_argument& e) {
    setError(error, e.what());
    return nullptr;
  }
}

// The rectifier of options.calibration_file; nullptr without one. False with a message when
// the file cannot be used.
bool loadRectifier(const SourceConfig& options, std::shared_ptr<const StereoRectifier>* out,
                   std::string* error) {
  out->reset();
  if (options.calibration_file.empty()) return true;
  try {
    const StereoCameraCalibration raw = loadStereoCalibration(options.calibration_file, true);
    *out = StereoRectifier::create(raw, error);
    return *out != nullptr;
  } catch (const CalibrationError& e) {
    setError(error, e.what());
    return false;
  }
}

std::unique_ptr<FrameSource> openV4l2(const std::string& kind, const std::string& what,
                                      const SourceConfig& options, std::string* error) {
  V4l2SourceConfig config = options.v4l2;
  config.devices = splitCommas(what);
  if (kind == "v4l2-stereo") {
    if (config.devices.size() != 2) {
      setError(error, "v4l2-stereo: needs two devices, left and right: "
                      "v4l2-stereo:/dev/videoL,/dev/videoR");
      return nullptr;
    }
    config.mode = V4l2Mode::kStereoPair;
  } else if (config.mode == V4l2Mode::kStereoPair) {
    setError(error, "v4l2:" + what + ": v4l2.mode stereo_pair needs the v4l2-stereo:L,R source");
    return nullptr;
  }
  std::shared_ptr<const StereoRectifier> rectifier;
  if (!loadRectifier(options, &rectifier, error)) return nullptr;
  return V4l2Source::open(config, std::move(rectifier), error);
}

std::unique_ptr<FrameSource> openLibcamera(const std::string& what, const SourceConfig& options,
                                           std::string* error) {
  LibcameraSourceConfig config = options.libcamera;
  config.camera.camera_id = what;
  if (!loadRectifier(options, &config.rectifier, error)) return nullptr;
  return LibcameraSource::open(config, error);
}

}  // namespace

std::shared_ptr<const Mesh> loadSimSceneMesh(const std::string& spec, std::string* error,
                                             std::vector<std::string>* warnings) {
  if (!spec.starts_with("sim:")) {
    setError(error, "'" + spec + "' is not a sim source");
    return nullptr;
  }
  const std::string what = spec.substr(4);
  if (isBuiltin(what)) return std::make_shared<const Mesh>(makeBuiltinScene(what).mesh);
  if (what.empty()) {
    setError(error, "sim: needs a scene: room, hall, town or a .ply/.obj mesh path");
    return nullptr;
  }
  SceneMeshReport report;
  std::optional<Mesh> mesh = loadSceneMesh(what, SceneMeshCheck{}, error, &report);
  if (!mesh.has_value()) return nullptr;
  if (warnings != nullptr) {
    warnings->insert(warnings->end(), report.warnings.begin(), report.warnings.end());
  }
  return std::make_shared<const Mesh>(std::move(*mesh));
}

bool isCameraSpec(const std::string& spec) {
  const std::string kind = spec.substr(0, spec.find(':'));
  return spec.find(':') != std::string::npos &&
         (kind == "v4l2" || kind == "v4l2-stereo" || kind == "libcamera");
}

std::unique_ptr<FrameSource> openFrameSource(const std::string& spec, const SourceConfig& options,
                                             std::string* error,
                                             std::vector<std::string>* warnings) {
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) {
    setError(error, "source '" + spec +
                        "' has no kind: use sim:room|hall|town|MESH, euroc:DIR, kitti:DIR, tum:DIR, "
                        "7scenes:DIR, v4l2:/dev/videoN, v4l2-stereo:/dev/videoL,/dev/videoR or "
                        "libcamera:CAMERA_ID");
    return nullptr;
  }
  const std::string kind = spec.substr(0, colon), what = spec.substr(colon + 1);
  if (!isCameraSpec(spec) && !options.calibration_file.empty() && warnings != nullptr) {
    warnings->push_back("calibration " + options.calibration_file +
                        " is for camera sources and is not used: " + kind +
                        " sources carry their own calibration");
  }
  if (kind == "sim") return openSim(what, options, error, warnings);
  if (kind == "euroc") {
    auto reader = EurocReader::open(what, options.euroc, error);
    if (!reader.has_value()) return nullptr;
    return std::make_unique<EurocSource>(std::move(*reader), options.max_frames);
  }
  if (kind == "kitti") {
    auto reader = KittiOdometryReader::open(what, error);
    if (!reader.has_value()) return nullptr;
    return std::make_unique<KittiSource>(std::move(*reader), options.max_frames);
  }
  if (kind == "tum") {
    auto reader = TumRgbdReader::open(what, options.tum, error);
    if (!reader.has_value()) return nullptr;
    return std::make_unique<TumRgbdSource>(std::move(*reader), options.max_frames);
  }
  if (kind == "7scenes") {
    auto reader = SevenScenesReader::open(what, error);
    if (!reader.has_value()) return nullptr;
    return std::make_unique<SevenScenesSource>(std::move(*reader), options.max_frames);
  }
  if (kind == "v4l2" || kind == "v4l2-stereo") return openV4l2(kind, what, options, error);
  if (kind == "libcamera") return openLibcamera(what, options, error);
  setError(error, "unknown source kind '" + kind +
                      "' (known: sim, euroc, kitti, tum, 7scenes, v4l2, v4l2-stereo, libcamera)");
  return nullptr;
}

}  // namespace cblox
