#include "daemon/capture/capture_config.h"

#include <cmath>

#include "daemon/common/input_silence.h"
#include "daemon/common/yaml_config.h"

namespace cblox {
namespace {

// `<name>_position: [x, y, z]` and `<name>_quaternion_wxyz: [w, x, y, z]` into *pose when
// either is given (the other defaults to zero / identity).
void readPose(const YAML::Node& node, const std::string& path, const std::string& name,
              Transformationd* pose) {
  std::vector<double> position, quaternion;
  const std::string position_key = name + "_position", quaternion_key = name + "_quaternion_wxyz";
  readOptional(node, path, position_key.c_str(), &position);
  readOptional(node, path, quaternion_key.c_str(), &quaternion);
  if (position.empty() && quaternion.empty()) return;
  if (position.empty()) position = {0.0, 0.0, 0.0};
  if (quaternion.empty()) quaternion = {1.0, 0.0, 0.0, 0.0};
  if (position.size() != 3 || quaternion.size() != 4) {
    throw ConfigError(path + ": " + position_key + " needs 3 numbers, " + quaternion_key + " 4");
  }
  const Eigen::Quaterniond q(quaternion[0], quaternion[1], quaternion[2], quaternion[3]);
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    throw ConfigError(path + "." + quaternion_key + ": norm must be 1");
  }
  *pose = Transformationd(q.normalized(), Eigen::Vector3d(position[0], position[1], position[2]));
}

void loadRig(const YAML::Node& node, SimRigConfig* rig) {
  const std::string path = "sim.rig";
  requireKnownKeys(node, path,
                   {"width", "height", "fx", "fy", "cx", "cy", "baseline_m", "right_cx_error_px", "depth_min_m",
                    "depth_max_m", "depth_width", "depth_height", "depth_fx", "depth_fy",
                    "depth_cx", "depth_cy", "T_L_D_position", "T_L_D_quaternion_wxyz"});
  if (isAbsent(node)) return;
  readOptional(node, path, "width", &rig->stereo.width);
  readOptional(node, path, "height", &rig->stereo.height);
  readOptional(node, path, "fx", &rig->stereo.fx);
  readOptional(node, path, "fy", &rig->stereo.fy);
  readOptional(node, path, "cx", &rig->stereo.cx);
  readOptional(node, path, "cy", &rig->stereo.cy);
  readOptional(node, path, "baseline_m", &rig->baseline_m);
  readOptional(node, path, "right_cx_error_px", &rig->right_cx_error_px);
  readOptional(node, path, "depth_min_m", &rig->depth_min_m);
  readOptional(node, path, "depth_max_m", &rig->depth_max_m);
  readOptional(node, path, "depth_width", &rig->depth.width);
  readOptional(node, path, "depth_height", &rig->depth.height);
  readOptional(node, path, "depth_fx", &rig->depth.fx);
  readOptional(node, path, "depth_fy", &rig->depth.fy);
  readOptional(node, path, "depth_cx", &rig->depth.cx);
  readOptional(node, path, "depth_cy", &rig->depth.cy);
  readPose(node, path, "T_L_D", &rig->T_L_D);
}

void loadNoise(const YAML::Node& node, SensorNoiseConfig* noise) {
  const std::string path = "sim.noise";
  requireKnownKeys(node, path,
                   {"preset", "image_noise_sigma", "exposure_amplitude", "exposure_period_s",
                    "exposure_time_s", "blur_samples", "depth_noise_per_m2",
                    "depth_hole_probability", "depth_edge_hole_probability",
                    "frame_drop_probability", "seed"});
  if (isAbsent(node)) return;
  std::string preset;
  readOptional(node, path, "preset", &preset);
  if (!preset.empty()) *noise = sensorNoisePreset(preset);
  readOptional(node, path, "image_noise_sigma", &noise->image_noise_sigma);
  readOptional(node, path, "exposure_amplitude", &noise->exposure_amplitude);
  readOptional(node, path, "exposure_period_s", &noise->exposure_period_s);
  readOptional(node, path, "exposure_time_s", &noise->exposure_time_s);
  readOptional(node, path, "blur_samples", &noise->blur_samples);
  readOptional(node, path, "depth_noise_per_m2", &noise->depth_noise_per_m2);
  readOptional(node, path, "depth_hole_probability", &noise->depth_hole_probability);
  readOptional(node, path, "depth_edge_hole_probability", &noise->depth_edge_hole_probability);
  readOptional(node, path, "frame_drop_probability", &noise->frame_drop_probability);
  readOptional(node, path, "seed", &noise->seed);
}

void loadIntrinsics(const YAML::Node& node, const std::string& path,
                    std::optional<PinholeIntrinsics>* out) {
  requireKnownKeys(node, path, {"width", "height", "fx", "fy", "cx", "cy"});
  if (isAbsent(node)) return;
  PinholeIntrinsics in;
  for (const char* key : {"width", "height", "fx", "fy", "cx", "cy"}) {
    if (!node[key]) throw ConfigError(path + "." + key + ": missing");
  }
  readOptional(node, path, "width", &in.width);
  readOptional(node, path, "height", &in.height);
  readOptional(node, path, "fx", &in.fx);
  readOptional(node, path, "fy", &in.fy);
  readOptional(node, path, "cx", &in.cx);
  readOptional(node, path, "cy", &in.cy);
  if (const std::string e = validate(in); !e.empty()) throw ConfigError(path + ": " + e);
  *out = in;
}

void loadV4l2(const YAML::Node& node, V4l2SourceConfig* v) {
  const std::string path = "v4l2";
  requireKnownKeys(node, path,
                   {"mode", "pixel_format", "width", "height", "rate_hz", "buffer_count",
                    "pair_tolerance_ms", "exposure", "gain", "depth_scale_m",
                    "depth_intrinsics", "T_B_D_position", "T_B_D_quaternion_wxyz",
                    "depth_min_m", "depth_max_m", "color", "reopen_min_s",
                    "reopen_max_s", "frame_timeout_s", "stalls_before_reopen"});
  if (isAbsent(node)) return;
  if (node["mode"]) {
    std::string mode;
    readOptional(node, path, "mode", &mode);
    const std::optional<V4l2Mode> parsed = v4l2ModeFromName(mode);
    if (!parsed) {
      throw ConfigError(path + ".mode must be mono, depth, stereo_pair or side_by_side, got '" +
                        mode + "'");
    }
    v->mode = *parsed;
  }
  readOptional(node, path, "pixel_format", &v->pixel_format);
  readOptional(node, path, "width", &v->width);
  readOptional(node, path, "height", &v->height);
  readOptional(node, path, "rate_hz", &v->rate_hz);
  readOptional(node, path, "buffer_count", &v->buffer_count);
  readOptional(node, path, "pair_tolerance_ms", &v->pair_tolerance_ms);
  if (node["exposure"]) v->exposure = node["exposure"].as<int>();
  if (node["gain"]) v->gain = node["gain"].as<int>();
  readOptional(node, path, "depth_scale_m", &v->depth_scale_m);
  loadIntrinsics(node["depth_intrinsics"], path + ".depth_intrinsics", &v->depth_intrinsics);
  readPose(node, path, "T_B_D", &v->T_B_D);
  readOptional(node, path, "depth_min_m", &v->depth_min_m);
  readOptional(node, path, "depth_max_m", &v->depth_max_m);
  readOptional(node, path, "color", &v->color);
  readOptional(node, path, "reopen_min_s", &v->reopen_min_s);
  readOptional(node, path, "reopen_max_s", &v->reopen_max_s);
  readOptional(node, path, "frame_timeout_s", &v->frame_timeout_s);
  readOptional(node, path, "stalls_before_reopen", &v->stalls_before_reopen);
  // The device count is the source spec's; check the rest with one device (two for pairs).
  V4l2SourceConfig check = *v;
  check.devices = check.mode == V4l2Mode::kStereoPair
                      ? std::vector<std::string>{"/dev/videoL", "/dev/videoR"}
                      : std::vector<std::string>{"/dev/video0"};
  if (const std::string e = check.validate(); !e.empty()) throw ConfigError(path + ": " + e);
}

void loadLibcamera(const YAML::Node& node, LibcameraSourceConfig* l) {
  const std::string path = "libcamera";
  requireKnownKeys(node, path,
                   {"mode", "pixel_format", "width", "height", "rate_hz", "buffer_count",
                    "exposure_us", "analogue_gain", "stall_timeout_s", "restart_backoff_s",
                    "restart_backoff_max_s"});
  if (isAbsent(node)) return;
  if (node["mode"]) {
    std::string mode;
    readOptional(node, path, "mode", &mode);
    const std::optional<LibcameraStereoMode> parsed = parseLibcameraStereoMode(mode);
    if (!parsed) throw ConfigError(path + ".mode must be mono or side_by_side, got '" + mode + "'");
    l->mode = *parsed;
  }
  readOptional(node, path, "pixel_format", &l->camera.pixel_format);
  readOptional(node, path, "width", &l->camera.width);
  readOptional(node, path, "height", &l->camera.height);
  readOptional(node, path, "rate_hz", &l->camera.rate_hz);
  readOptional(node, path, "buffer_count", &l->camera.buffer_count);
  if (node["exposure_us"]) l->camera.exposure_us = node["exposure_us"].as<int>();
  if (node["analogue_gain"]) l->camera.analogue_gain = node["analogue_gain"].as<double>();
  readOptional(node, path, "stall_timeout_s", &l->stall_timeout_s);
  readOptional(node, path, "restart_backoff_s", &l->restart_backoff_s);
  readOptional(node, path, "restart_backoff_max_s", &l->restart_backoff_max_s);
  if (const std::string e = l->validate(); !e.empty()) throw ConfigError(path + ": " + e);
}

void loadStereoDepth(const YAML::Node& node, CaptureConfig* config) {
  const std::string path = "stereo_depth";
  requireKnownKeys(node, path,
                   {"matcher", "downscale", "num_disparities", "block_size", "uniqueness_ratio",
                    "left_right_max_diff", "speckle_window", "speckle_range",
                    "texture_threshold", "min_depth_m", "max_depth_m", "max_rate_hz"});
  if (isAbsent(node)) return;
  std::string matcher = "none";
  readOptional(node, path, "matcher", &matcher);
  StereoDepthConfig stereo;
  if (matcher != "none" && !parseStereoMatcher(matcher, &stereo.matcher)) {
    throw ConfigError(path + ".matcher must be none, sgbm, sgbm3way or bm, got '" + matcher +
                      "'");
  }
  readOptional(node, path, "downscale", &stereo.downscale);
  readOptional(node, path, "num_disparities", &stereo.num_disparities);
  readOptional(node, path, "block_size", &stereo.block_size);
  readOptional(node, path, "uniqueness_ratio", &stereo.uniqueness_ratio);
  readOptional(node, path, "left_right_max_diff", &stereo.left_right_max_diff);
  readOptional(node, path, "speckle_window", &stereo.speckle_window);
  readOptional(node, path, "speckle_range", &stereo.speckle_range);
  readOptional(node, path, "texture_threshold", &stereo.texture_threshold);
  readOptional(node, path, "min_depth_m", &stereo.min_depth_m);
  readOptional(node, path, "max_depth_m", &stereo.max_depth_m);
  readOptional(node, path, "max_rate_hz", &config->stereo_depth_max_rate_hz);
  if (!(config->stereo_depth_max_rate_hz >= 0.0) ||
      !std::isfinite(config->stereo_depth_max_rate_hz)) {
    throw ConfigError(path + ".max_rate_hz must be >= 0");
  }
  if (const std::string e = stereo.validate(); !e.empty()) throw ConfigError(path + "." + e);
  config->stereo_depth.reset();
  if (matcher != "none") config->stereo_depth = stereo;
}

}  // namespace

SensorNoiseConfig sensorNoisePreset(const std::string& name) {
  SensorNoiseConfig noise;
  if (name == "none") return noise;
  if (name == "realistic") {
    noise.image_noise_sigma = 2.0;
    noise.exposure_amplitude = 0.15;
    noise.exposure_period_s = 7.0;
    noise.depth_noise_per_m2 = 0.0012;
    noise.depth_hole_probability = 0.01;
    noise.depth_edge_hole_probability = 0.5;
    return noise;
  }
  throw ConfigError("noise preset must be none or realistic, got '" + name + "'");
}

void parsePacing(const std::string& text, CaptureConfig* config) {
  if (text == "source") {
    config->pacing = CapturePacing::kSource;
    return;
  }
  if (text == "max") {
    config->pacing = CapturePacing::kMax;
    return;
  }
  char* end = nullptr;
  const double hz = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !(hz > 0.0) || !std::isfinite(hz)) {
    throw ConfigError("rate must be 'source', 'max' or a rate in Hz > 0, got '" + text + "'");
  }
  config->pacing = CapturePacing::kFixed;
  config->fixed_rate_hz = hz;
}

CaptureConfig loadCaptureConfig(const YAML::Node& root) {
  CaptureConfig config;
  requireKnownKeys(root, "capture",
                   {"source", "trajectory", "laps", "rate", "frames", "lcm_url", "channels",
                    "publish", "depth_encoding", "input_silence_s", "sim", "stereo_depth",
                    "calibration", "v4l2", "libcamera", "device_wait_s"});
  if (isAbsent(root)) return config;
  readOptional(root, "capture", "source", &config.source);
  readOptional(root, "capture", "trajectory", &config.source_config.trajectory);
  readOptional(root, "capture", "laps", &config.source_config.laps);
  if (root["rate"]) {
    std::string rate;
    readOptional(root, "capture", "rate", &rate);
    parsePacing(rate, &config);
  }
  int frames = 0;
  readOptional(root, "capture", "frames", &frames);
  if (frames < 0) throw ConfigError("capture.frames must be >= 0, got " + std::to_string(frames));
  config.source_config.max_frames = static_cast<size_t>(frames);
  readOptional(root, "capture", "lcm_url", &config.lcm_url);
  readOptional(root, "capture", "input_silence_s", &config.input_silence_s);
  if (const std::string e = validateInputSilence(config.input_silence_s); !e.empty()) {
    throw ConfigError("capture." + e);
  }
  const YAML::Node channels = root["channels"];
  requireKnownKeys(channels, "channels", {"stereo", "depth", "ground_truth", "heartbeat"});
  if (!isAbsent(channels)) {
    readOptional(channels, "channels", "stereo", &config.stereo_channel);
    readOptional(channels, "channels", "depth", &config.depth_channel);
    readOptional(channels, "channels", "ground_truth", &config.ground_truth_channel);
    readOptional(channels, "channels", "heartbeat", &config.heartbeat_channel);
  }
  const YAML::Node publish = root["publish"];
  requireKnownKeys(publish, "publish", {"stereo", "depth", "ground_truth"});
  if (!isAbsent(publish)) {
    readOptional(publish, "publish", "stereo", &config.publish_stereo);
    readOptional(publish, "publish", "depth", &config.publish_depth);
    readOptional(publish, "publish", "ground_truth", &config.publish_ground_truth);
  }
  readOptionalEnum(root, "capture", "depth_encoding",
                   {{"u16_mm", DepthEncoding::kUint16Millimetres},
                    {"f32", DepthEncoding::kFloat32Metres}},
                   &config.depth_encoding);
  const YAML::Node sim = root["sim"];
  requireKnownKeys(sim, "sim", {"rate_hz", "threads", "rig", "noise", "keep_rig_range"});
  if (!isAbsent(sim)) {
    SimSourceConfig& s = config.source_config.sim;
    readOptional(sim, "sim", "rate_hz", &s.rate_hz);
    readOptional(sim, "sim", "threads", &s.renderer.num_threads);
    readOptional(sim, "sim", "keep_rig_range", &config.source_config.keep_rig_range);
    loadRig(sim["rig"], &s.renderer.rig);
    loadNoise(sim["noise"], &s.noise);
    if (const std::string problem = s.validate(); !problem.empty()) {
      throw ConfigError("sim: " + problem);
    }
  }
  loadStereoDepth(root["stereo_depth"], &config);
  readOptional(root, "capture", "calibration", &config.source_config.calibration_file);
  readOptional(root, "capture", "device_wait_s", &config.device_wait_s);
  if (!(config.device_wait_s >= 0.0) || !std::isfinite(config.device_wait_s)) {
    throw ConfigError("capture.device_wait_s must be >= 0 seconds");
  }
  try {
    loadV4l2(root["v4l2"], &config.source_config.v4l2);
    loadLibcamera(root["libcamera"], &config.source_config.libcamera);
  } catch (const YAML::Exception& e) {
    throw ConfigError(std::string("capture: ") + e.what());
  }
  if (config.source_config.laps < 1) throw ConfigError("capture.laps must be >= 1");
  return config;
}

}  // namespace cblox
