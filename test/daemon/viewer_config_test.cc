// cblox-viewer's settings: the shipped config/viewer.yaml is the built-in defaults; every key is
// read; bad keys and values are refused naming them.

#include "daemon/viewer/viewer_config.h"

#include <gtest/gtest.h>

#include "daemon/common/yaml_config.h"

namespace cblox {
namespace {

TEST(ViewerConfigTest, ShippedYamlMatchesTheCodeDefaults) {
  const ViewerConfig shipped =
      loadViewerConfig(loadYamlFile(std::string(CBLOX_CONFIG_DIR) + "/viewer.yaml"));
  const ViewerConfig d;
  EXPECT_EQ(shipped.lcm_url, d.lcm_url);
  EXPECT_EQ(shipped.mesh_update_channel, d.mesh_update_channel);
  EXPECT_EQ(shipped.subvolumes_channel, d.subvolumes_channel);
  EXPECT_EQ(shipped.frame_pose_channel, d.frame_pose_channel);
  EXPECT_EQ(shipped.ground_truth_channel, d.ground_truth_channel);
  EXPECT_EQ(shipped.keyframe_channel, d.keyframe_channel);
  EXPECT_EQ(shipped.keyframe_poses_channel, d.keyframe_poses_channel);
  EXPECT_EQ(shipped.map_status_channel, d.map_status_channel);
  EXPECT_EQ(shipped.heartbeat_channel, d.heartbeat_channel);
  EXPECT_EQ(shipped.local_grid_channel, d.local_grid_channel);
  EXPECT_EQ(shipped.command_channel, d.command_channel);
  EXPECT_EQ(shipped.command_reply_channel, d.command_reply_channel);
  EXPECT_EQ(shipped.bind_address, "127.0.0.1");
  EXPECT_EQ(shipped.bind_address, d.bind_address);
  EXPECT_EQ(shipped.port, d.port);
  EXPECT_EQ(shipped.max_clients, d.max_clients);
  EXPECT_EQ(shipped.client_timeout_s, d.client_timeout_s);
  EXPECT_EQ(shipped.max_message_bytes, d.max_message_bytes);
  EXPECT_FALSE(shipped.allow_export);
  EXPECT_EQ(shipped.allow_export, d.allow_export);
  EXPECT_EQ(shipped.web_root, d.web_root);
  EXPECT_EQ(shipped.three_js_dir, d.three_js_dir);
  EXPECT_EQ(shipped.up_axis, d.up_axis);
  EXPECT_EQ(shipped.max_trajectory_points, d.max_trajectory_points);
  EXPECT_EQ(shipped.status_period_s, d.status_period_s);
  EXPECT_EQ(shipped.refresh_retry_s, d.refresh_retry_s);
  EXPECT_EQ(d.validate(), "");
}

TEST(ViewerConfigTest, ReadsEveryKey) {
  const ViewerConfig c = loadViewerConfig(YAML::Load(
      "lcm_url: memq://\n"
      "channels: {mesh_update: MU, subvolumes: SV, frame_pose: FP, ground_truth_pose: GT,\n"
      "  keyframe: KF, keyframe_poses: KP, map_status: MS, heartbeat: HB, local_grid: LG,\n"
      "  command: C, command_reply: CR}\n"
      "bind_address: 0.0.0.0\nport: 9000\nmax_clients: 2\nclient_timeout_s: 3\n"
      "max_message_bytes: 100000\nallow_export: true\nweb_root: /w\nthree_js_dir: /t\n"
      "up_axis: -y\nmax_trajectory_points: 500\nstatus_period_s: 2\nrefresh_retry_s: 1\n"));
  EXPECT_EQ(c.lcm_url, "memq://");
  EXPECT_EQ(c.mesh_update_channel, "MU");
  EXPECT_EQ(c.subvolumes_channel, "SV");
  EXPECT_EQ(c.frame_pose_channel, "FP");
  EXPECT_EQ(c.ground_truth_channel, "GT");
  EXPECT_EQ(c.keyframe_channel, "KF");
  EXPECT_EQ(c.keyframe_poses_channel, "KP");
  EXPECT_EQ(c.map_status_channel, "MS");
  EXPECT_EQ(c.heartbeat_channel, "HB");
  EXPECT_EQ(c.local_grid_channel, "LG");
  EXPECT_EQ(c.command_channel, "C");
  EXPECT_EQ(c.command_reply_channel, "CR");
  EXPECT_EQ(c.bind_address, "0.0.0.0");
  EXPECT_EQ(c.port, 9000);
  EXPECT_EQ(c.max_clients, 2);
  EXPECT_EQ(c.client_timeout_s, 3.0);
  EXPECT_EQ(c.max_message_bytes, 100000u);
  EXPECT_TRUE(c.allow_export);
  EXPECT_EQ(c.web_root, "/w");
  EXPECT_EQ(c.resolvedWebRoot(), "/w");
  EXPECT_EQ(c.three_js_dir, "/t");
  EXPECT_EQ(c.up_axis, "-y");
  EXPECT_EQ(c.max_trajectory_points, 500u);
  EXPECT_EQ(c.status_period_s, 2.0);
  EXPECT_EQ(c.refresh_retry_s, 1.0);
}

TEST(ViewerConfigTest, RejectsBadKeysAndValuesNamingThem) {
  const std::pair<const char*, const char*> cases[] = {
      {"prot: 80\n", "prot"},
      {"port: 0\n", "port"},
      {"port: 70000\n", "port"},
      {"max_clients: 0\n", "max_clients"},
      {"max_clients: 64\n", "max_clients"},
      {"client_timeout_s: 0\n", "client_timeout_s"},
      {"max_message_bytes: 10\n", "max_message_bytes"},
      {"up_axis: up\n", "up_axis"},
      {"max_trajectory_points: 5\n", "max_trajectory_points"},
      {"bind_address: ''\n", "bind_address"},
      {"channels: {mesh: X}\n", "mesh"},
      {"allow_export: maybe\n", "allow_export"},
      {"refresh_retry_s: -1\n", "refresh_retry_s"},
  };
  for (const auto& [yaml, key] : cases) {
    try {
      loadViewerConfig(YAML::Load(yaml));
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace cblox
