#pragma once

// Settings of cblox-viewer (config/viewer.yaml): LCM and channels, the web server, limits on
// browsers, and where the page's files are. Plain value type; loadViewerConfig reads YAML.

#include <cstddef>
#include <string>

#include <yaml-cpp/yaml.h>

namespace cblox {

struct ViewerConfig {
  /// LCM provider URL; empty means LCM's default.
  std::string lcm_url;
  std::string mesh_update_channel = "CBLOX_MESH_UPDATE";
  std::string subvolumes_channel = "CBLOX_SUBVOLUMES";
  std::string frame_pose_channel = "CBLOX_FRAME_POSE";
  std::string ground_truth_channel = "CBLOX_GT_POSE";
  std::string keyframe_channel = "CBLOX_KEYFRAME";
  std::string keyframe_poses_channel = "CBLOX_KEYFRAME_POSES";
  std::string map_status_channel = "CBLOX_MAP_STATUS";
  std::string heartbeat_channel = "CBLOX_HEARTBEAT";
  std::string local_grid_channel = "CBLOX_LOCAL_GRID";
  std::string command_channel = "CBLOX_CMD";
  std::string command_reply_channel = "CBLOX_CMD_REPLY";

  /// Address the web server binds to. 127.0.0.1 (the default) serves this computer only;
  /// any other address (0.0.0.0: every interface) lets anyone who reaches it watch the map,
  /// and with allow_export ask the mapper for exports: only on a trusted network.
  std::string bind_address = "127.0.0.1";
  /// TCP port, [1, 65535].
  int port = 8090;
  /// Browsers connected at once, [1, 32]; more are refused (counted).
  int max_clients = 4;
  /// A browser that has not taken what it was sent for this long is disconnected (counted),
  /// seconds, (0, 600].
  double client_timeout_s = 10.0;
  /// Mesh bytes one message to a browser carries at most, [64 KiB, 16 MiB]; a browser that is
  /// behind gets the newest state of every block in messages of this size.
  size_t max_message_bytes = size_t{1} << 20;
  /// The page's Export button asks the mapper for export_mesh and offers the PLY; off: the
  /// viewer is read-only (the button is hidden and requests are refused, counted).
  bool allow_export = false;
  /// Where the page's own files are (index.html, viewer.js, viewer.css); empty: the
  /// installed ones (<prefix>/share/cblox/viewer), or the source tree's when cblox-viewer
  /// runs from its build folder (resolvedWebRoot()).
  std::string web_root;
  /// Where three.js is (Debian's libjs-three: three.min.js and
  /// examples/js/controls/OrbitControls.js under it).
  std::string three_js_dir = "/usr/share/javascript/three";
  /// The up axis of the map's frame G for height colours and the camera: z (the simulator,
  /// ground-truth poses), -y (the tracker's G is its first camera frame), or any of x, y, z,
  /// -x, -y, -z.
  std::string up_axis = "z";
  /// Frame positions kept for the trajectory (the oldest are thinned), [100, 1000000].
  size_t max_trajectory_points = 20000;
  /// Heartbeat period, seconds (> 0).
  double status_period_s = 1.0;
  /// While the mesh is incomplete (started late, a lost message), ask the mapper for a
  /// refresh at most this often, seconds (> 0).
  double refresh_retry_s = 5.0;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
  /// web_root, or when it is empty the installed page if it is there, else the source
  /// tree's daemon/viewer/web. Thread-safe.
  std::string resolvedWebRoot() const;
};

/// The settings in a YAML document (config/viewer.yaml's keys; absent keys keep the
/// defaults). Throws ConfigError naming the key for unknown keys and bad values.
ViewerConfig loadViewerConfig(const YAML::Node& root);

}  // namespace cblox
