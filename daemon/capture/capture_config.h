#pragma once

#include <optional>
#include <string>

#include <yaml-cpp/yaml.h>

#include "daemon/common/input_silence.h"
#include "daemon/common/lcm_messages.h"
#include "drivers/open_frame_source.h"
#include "drivers/stereo_depth/stereo_depth.h"

namespace cblox {

/// How fast cblox-capture plays a source.
enum class CapturePacing {
  kSource,  ///< at the source's own time stamps (real time)
  kMax,     ///< as fast as possible
  kFixed,   ///< at a fixed rate (fixed_rate_hz), whatever the source's stamps
};

/// Settings of cblox-capture (config/capture.yaml). Plain value type.
struct CaptureConfig {
  std::string source = "sim:room";
  SourceConfig source_config;
  CapturePacing pacing = CapturePacing::kSource;
  double fixed_rate_hz = 0.0;
  /// LCM provider URL; empty means LCM's default (udpm://239.255.76.67:7667?ttl=0).
  std::string lcm_url;
  std::string stereo_channel = "CBLOX_STEREO";
  std::string depth_channel = "CBLOX_DEPTH";
  std::string ground_truth_channel = "CBLOX_GT_POSE";
  std::string heartbeat_channel = "CBLOX_HEARTBEAT";
  bool publish_stereo = true;
  bool publish_depth = true;
  bool publish_ground_truth = true;
  DepthEncoding depth_encoding = DepthEncoding::kUint16Millimetres;
  /// Input-silence health (daemon/common/input_watch.h): the heartbeat reports the frame
  /// source silent when it produced no frame for this long, seconds; 0 = off. Set it above
  /// the frame period when playing slower than 0.5 Hz.
  double input_silence_s = kDefaultInputSilenceS;
  /// Camera sources: how long a camera that cannot be opened yet (missing, busy) is waited
  /// for at start, retried once a second, before its error ends the process (exit 2);
  /// 0 = fail at once. The systemd unit waits 45 s (cameras enumerating at boot).
  double device_wait_s = 0.0;
  /// Dense stereo depth (`stereo_depth:`): when set, depth is computed from the rectified pair
  /// on a thread of its own and published on depth_channel in place of the source's depth
  /// camera (rigs without one; the simulator with its depth camera switched off).
  std::optional<StereoDepthConfig> stereo_depth;
  /// Depth frames per second of frame time at the most; 0 = as many as the matcher keeps up
  /// with (newest pair wins).
  double stereo_depth_max_rate_hz = 0.0;
};

/// The sensor-noise presets: "none" (exact images) and "realistic" (image noise 2 grey
/// levels, exposure drift 15 % over 7 s, depth noise 0.0012 z^2, 1 % holes, half of the
/// depth-edge pixels missing, no frame drops).
SensorNoiseConfig sensorNoisePreset(const std::string& name);  // throws ConfigError

/// Parses "source" / "max" / a rate in Hz into *config. Throws ConfigError.
void parsePacing(const std::string& text, CaptureConfig* config);

/// Reads the YAML tree of config/capture.yaml over the defaults; throws ConfigError naming
/// the key for unknown keys or bad values.
CaptureConfig loadCaptureConfig(const YAML::Node& root);

}  // namespace cblox
