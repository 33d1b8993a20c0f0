#include "daemon/viewer/viewer_config.h"

#include <cmath>
#include <filesystem>

#include "daemon/common/yaml_config.h"

namespace cblox {

std::string ViewerConfig::validate() const {
  if (port < 1 || port > 65535) return "port must be in [1, 65535], got " + std::to_string(port);
  if (bind_address.empty()) return "bind_address must not be empty";
  if (max_clients < 1 || max_clients > 32) {
    return "max_clients must be in [1, 32], got " + std::to_string(max_clients);
  }
  if (!std::isfinite(client_timeout_s) || client_timeout_s <= 0.0 || client_timeout_s > 600.0) {
    return "client_timeout_s must be in (0, 600], got " + std::to_string(client_timeout_s);
  }
  if (max_message_bytes < (size_t{64} << 10) || max_message_bytes > (size_t{16} << 20)) {
    return "max_message_bytes must be in [65536, 16777216], got " +
           std::to_string(max_message_bytes);
  }
  static const char* const kAxes[] = {"x", "y", "z", "-x", "-y", "-z"};
  bool axis_ok = false;
  for (const char* a : kAxes) axis_ok = axis_ok || up_axis == a;
  if (!axis_ok) return "up_axis must be x, y, z, -x, -y or -z, got '" + up_axis + "'";
  if (max_trajectory_points < 100 || max_trajectory_points > 1000000) {
    return "max_trajectory_points must be in [100, 1000000], got " +
           std::to_string(max_trajectory_points);
  }
  if (!std::isfinite(status_period_s) || status_period_s <= 0.0) {
    return "status_period_s must be finite and > 0";
  }
  if (!std::isfinite(refresh_retry_s) || refresh_retry_s <= 0.0) {
    return "refresh_retry_s must be finite and > 0";
  }
  return {};
}

std::string ViewerConfig::resolvedWebRoot() const {
  if (!web_root.empty()) return web_root;
  const std::filesystem::path installed(CBLOX_VIEWER_WEB_ROOT);
  if (std::filesystem::is_regular_file(installed / "index.html")) return installed.string();
  return CBLOX_VIEWER_SOURCE_WEB_ROOT;
}

ViewerConfig loadViewerConfig(const YAML::Node& root) {
  ViewerConfig c;
  const std::string top = "viewer";
  requireKnownKeys(root, top,
                   {"lcm_url", "channels", "bind_address", "port", "max_clients",
                    "client_timeout_s", "max_message_bytes", "allow_export", "web_root",
                    "three_js_dir", "up_axis", "max_trajectory_points", "status_period_s",
                    "refresh_retry_s"});
  if (isAbsent(root)) return c;
  readOptional(root, top, "lcm_url", &c.lcm_url);
  const YAML::Node channels = root["channels"];
  requireKnownKeys(channels, "channels",
                   {"mesh_update", "subvolumes", "frame_pose", "ground_truth_pose", "keyframe",
                    "keyframe_poses", "map_status", "heartbeat", "local_grid", "command",
                    "command_reply"});
  if (!isAbsent(channels)) {
    readOptional(channels, "channels", "mesh_update", &c.mesh_update_channel);
    readOptional(channels, "channels", "subvolumes", &c.subvolumes_channel);
    readOptional(channels, "channels", "frame_pose", &c.frame_pose_channel);
    readOptional(channels, "channels", "ground_truth_pose", &c.ground_truth_channel);
    readOptional(channels, "channels", "keyframe", &c.keyframe_channel);
    readOptional(channels, "channels", "keyframe_poses", &c.keyframe_poses_channel);
    readOptional(channels, "channels", "map_status", &c.map_status_channel);
    readOptional(channels, "channels", "heartbeat", &c.heartbeat_channel);
    readOptional(channels, "channels", "local_grid", &c.local_grid_channel);
    readOptional(channels, "channels", "command", &c.command_channel);
    readOptional(channels, "channels", "command_reply", &c.command_reply_channel);
  }
  readOptional(root, top, "bind_address", &c.bind_address);
  readOptional(root, top, "port", &c.port);
  readOptional(root, top, "max_clients", &c.max_clients);
  readOptional(root, top, "client_timeout_s", &c.client_timeout_s);
  readOptional(root, top, "max_message_bytes", &c.max_message_bytes);
  readOptional(root, top, "allow_export", &c.allow_export);
  readOptional(root, top, "web_root", &c.web_root);
  readOptional(root, top, "three_js_dir", &c.three_js_dir);
  readOptional(root, top, "up_axis", &c.up_axis);
  readOptional(root, top, "max_trajectory_points", &c.max_trajectory_points);
  readOptional(root, top, "status_period_s", &c.status_period_s);
  readOptional(root, top, "refresh_retry_s", &c.refresh_retry_s);
  if (const std::string e = c.validate(); !e.empty()) throw ConfigError(top + ": " + e);
  return c;
}

}  // namespace cblox
