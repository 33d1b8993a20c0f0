#pragma once

// Test helpers: one filled sample message per cblox LCM type, with distinctive non-default
// values (strings, non-empty arrays, nested members that differ from each other through
// `seed`). Shared by the round-trip tests (test_lcmtypes_roundtrip.cc), which check some
// of these values field by field, and the wire-check tests (wire_check_test.cc).
// Test-only; thread-safe (no shared state).

#include <cblox/camera_calibration_t.hpp>
#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/covariance_pair_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/depth_frame_t.hpp>
#include <cblox/distance_reply_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/image_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/local_grid_t.hpp>
#include <cblox/map_status_t.hpp>
#include <cblox/mesh_block_t.hpp>
#include <cblox/mesh_update_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/pose_t.hpp>
#include <cblox/stereo_pair_t.hpp>
#include <cblox/subvolume_list_t.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace cblox::test {

inline cblox::pose_t MakePose(double seed) {
  cblox::pose_t p{};
  p.position[0] = 1.25 + seed;
  p.position[1] = -2.5 - seed;
  p.position[2] = 3.75 * (seed + 1.0);
  // Not normalised on purpose: the wire format must carry the values unchanged.
  p.orientation[0] = 0.5 + seed;
  p.orientation[1] = -0.25;
  p.orientation[2] = 0.125 * (seed + 2.0);
  p.orientation[3] = -0.0625 - seed;
  return p;
}

inline cblox::image_t MakeImage(const std::string& camera_id, int8_t format, int32_t width,
                                int32_t height, int32_t bytes_per_pixel, uint8_t seed) {
  cblox::image_t img{};
  img.utime = 1'700'000'000'123'456 + seed;
  img.camera_id = camera_id;
  img.width = width;
  img.height = height;
  img.row_stride = width * bytes_per_pixel + 2;  // with padding
  img.pixel_format = format;
  img.depth_scale = format == cblox::image_t::DEPTH_U16 ? 0.001 : 1.0;
  img.size = img.row_stride * img.height;
  img.data.resize(static_cast<std::size_t>(img.size));
  for (std::size_t i = 0; i < img.data.size(); ++i) {
    img.data[i] = static_cast<uint8_t>(i * 7U + seed);
  }
  return img;
}

inline cblox::camera_calibration_t MakeCalibration(const std::string& camera_id,
                                                   double seed) {
  cblox::camera_calibration_t c{};
  c.camera_id = camera_id;
  c.width = 752;
  c.height = 480;
  c.fx = 458.654 + seed;
  c.fy = 457.296 + seed;
  c.cx = 367.215 - seed;
  c.cy = 248.375 - seed;
  c.distortion_model = "radtan";
  c.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05 + seed};
  c.num_distortion = static_cast<int8_t>(c.distortion.size());
  c.T_B_C = MakePose(seed + 0.5);
  return c;
}

inline cblox::pose_stamped_t MakePoseStamped() {
  cblox::pose_stamped_t m{};
  m.utime = 1'700'000'000'000'001;
  m.frame_id = 4242;
  m.frame = "G";
  m.T_G_C = MakePose(0.25);
  return m;
}

inline cblox::stereo_pair_t MakeStereoPair() {
  cblox::stereo_pair_t m{};
  m.utime = 1'700'000'000'000'002;
  m.frame_id = 77;
  m.left = MakeImage("cam0", cblox::image_t::GRAY8, 5, 4, 1, 11);
  m.right = MakeImage("cam1", cblox::image_t::RGB8, 3, 2, 3, 29);
  m.left_calibration = MakeCalibration("cam0", 0.0);
  m.right_calibration = MakeCalibration("cam1", 1.5);
  m.T_L_R = MakePose(-0.11);
  m.rectified = 1;
  return m;
}

inline cblox::depth_frame_t MakeDepthFrame() {
  cblox::depth_frame_t m{};
  m.utime = 1'700'000'000'000'003;
  m.frame_id = 78;
  m.depth = MakeImage("depth", cblox::image_t::DEPTH_U16, 4, 3, 2, 3);
  m.has_color = 1;
  m.color = MakeImage("depth", cblox::image_t::RGBA8, 4, 3, 4, 200);
  m.calibration = MakeCalibration("depth", 2.0);
  m.min_depth_m = 0.3F;
  m.max_depth_m = 4.5F;
  return m;
}

inline cblox::frame_pose_t MakeFramePose() {
  cblox::frame_pose_t m{};
  m.utime = 1'700'000'000'000'004;
  m.frame_id = 79;
  m.T_G_C = MakePose(3.0);
  m.tracking_state = cblox::frame_pose_t::LOOP_CORRECTED;
  m.tracking_jump = 1;
  m.map_epoch = 3;
  m.reference_keyframe_id = 4321;
  return m;
}

inline cblox::keyframe_t MakeKeyframe() {
  cblox::keyframe_t m{};
  m.utime = 1'700'000'000'000'005;
  m.map_epoch = 3;
  m.keyframe_id = 12;
  m.frame_id = 80;
  m.T_G_K = MakePose(4.0);
  m.landmark_ids = {5, 1'000'000'000'007, -3, 99};
  m.num_landmarks = static_cast<int32_t>(m.landmark_ids.size());
  return m;
}

inline cblox::keyframe_pose_batch_t MakeKeyframePoseBatch() {
  cblox::keyframe_pose_batch_t m{};
  m.utime = 1'700'000'000'000'006;
  m.map_epoch = 3;
  m.reason = cblox::keyframe_pose_batch_t::GLOBAL_BA;
  m.keyframe_ids = {12, 13, 21};
  m.poses = {MakePose(5.0), MakePose(6.0), MakePose(7.0)};
  m.num_keyframes = static_cast<int32_t>(m.keyframe_ids.size());
  return m;
}

inline cblox::covariance_request_t MakeCovarianceRequest() {
  cblox::covariance_request_t m{};
  m.utime = 1'700'000'000'000'007;
  m.map_epoch = 3;
  m.request_id = 901;
  m.keyframe_i = {12, 13};
  m.keyframe_j = {40, 41};
  m.num_pairs = static_cast<int32_t>(m.keyframe_i.size());
  return m;
}

inline cblox::covariance_pair_t MakeCovariancePair(int64_t i, int64_t j, bool ok) {
  cblox::covariance_pair_t p{};
  p.keyframe_i = i;
  p.keyframe_j = j;
  p.ok = ok ? 1 : 0;
  p.error = ok ? "" : "keyframe not in graph";
  for (int k = 0; k < 36; ++k) p.sigma_i_given_j[k] = 0.001 * (k + 1) + static_cast<double>(i);
  p.q = 0.0375 * static_cast<double>(j);
  return p;
}

inline cblox::covariance_reply_t MakeCovarianceReply() {
  cblox::covariance_reply_t m{};
  m.utime = 1'700'000'000'000'008;
  m.map_epoch = 3;
  m.request_id = 901;
  m.pairs = {MakeCovariancePair(12, 40, true), MakeCovariancePair(13, 41, false)};
  m.num_pairs = static_cast<int32_t>(m.pairs.size());
  return m;
}

inline cblox::command_t MakeCommand() {
  cblox::command_t m{};
  m.utime = 1'700'000'000'000'009;
  m.command_id = 31337;
  m.sender = "cblox-ctl";
  m.name = "export_mesh";
  m.arg_keys = {"path", "voxel_size"};
  m.arg_values = {"/tmp/mesh.ply", "0.05"};
  m.num_args = static_cast<int32_t>(m.arg_keys.size());
  return m;
}

inline cblox::command_reply_t MakeCommandReply() {
  cblox::command_reply_t m{};
  m.utime = 1'700'000'000'000'010;
  m.command_id = 31337;
  m.ok = 1;
  m.message = "mesh written";
  m.value_keys = {"path", "num_triangles", "empty"};
  m.values = {"/tmp/mesh.ply", "12345", ""};
  m.num_values = static_cast<int32_t>(m.value_keys.size());
  return m;
}

inline cblox::map_status_t MakeMapStatus() {
  cblox::map_status_t m{};
  m.utime = 1'700'000'000'000'011;
  m.num_subvolumes = 17;
  m.active_subvolume_id = 16;
  m.num_blocks = 123'456;
  m.memory_bytes = 5'000'000'123;
  m.frames_received = 1001;
  m.frames_integrated = 950;
  m.frames_dropped = 40;
  m.frames_rejected = 11;
  m.integration_ms_last = 12.5F;
  m.integration_ms_median = 10.25F;
  m.integration_ms_p99 = 31.75F;
  m.fusion_candidates = 9;
  m.covariance_requested = 8;
  m.subvolumes_fused = 5;
  m.rejected_by_q = 2;
  return m;
}

inline cblox::heartbeat_t MakeHeartbeat() {
  cblox::heartbeat_t m{};
  m.utime = 1'700'000'000'000'012;
  m.process = "cblox-mapper";
  m.pid = 4711;
  m.state = "running";
  m.counter_names = {"frames_in", "frames_out"};
  m.counter_values = {1'000'000'000'000, -1};
  m.num_counters = static_cast<int32_t>(m.counter_names.size());
  return m;
}

/// A distance request for `points` (x, y, z each).
inline cblox::distance_request_t MakeDistanceRequest(int64_t id, int64_t epoch,
                                                     std::vector<std::vector<double>> points) {
  cblox::distance_request_t m{};
  m.utime = 1'700'000'000'000'014;
  m.request_id = id;
  m.map_epoch = epoch;
  m.points = std::move(points);
  m.num_points = static_cast<int32_t>(m.points.size());
  return m;
}

inline cblox::distance_request_t MakeDistanceRequest() {
  return MakeDistanceRequest((int64_t{4242} << 32) | 7, 1'700'000'000'000'000,
                             {{0.5, -1.25, 0.75}, {2.0, 0.0, 1.5}, {-3.5, 4.0, 0.25}});
}

inline cblox::distance_reply_t MakeDistanceReply() {
  cblox::distance_reply_t m{};
  m.utime = 1'700'000'000'000'015;
  m.request_id = (int64_t{4242} << 32) | 7;
  m.map_epoch = 1'700'000'000'000'000;
  m.status = cblox::distance_reply_t::STATUS_OK;
  m.message = "";
  m.max_distance_m = 2.0f;
  m.state = {cblox::distance_reply_t::FREE, cblox::distance_reply_t::OCCUPIED,
             cblox::distance_reply_t::UNKNOWN};
  m.distance = {0.625f, -0.03125f, 0.0f};
  m.gradient = {{0.0f, 0.0f, 1.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
  m.num_points = static_cast<int32_t>(m.state.size());
  return m;
}

inline cblox::local_grid_t MakeLocalGrid() {
  cblox::local_grid_t m{};
  m.utime = 1'700'000'000'000'016;
  m.map_epoch = 1'700'000'000'000'000;
  m.pose_utime = 1'700'000'000'000'012;
  m.origin[0] = -4.0;
  m.origin[1] = -4.0;
  m.origin[2] = -0.5;
  m.resolution = 0.25;
  m.size[0] = 2;
  m.size[1] = 1;
  m.size[2] = 1;
  m.max_distance_m = 2.0f;
  m.encoding = cblox::local_grid_t::ENCODING_RAW;
  // Two cells: free at 0.5 m, unknown (little-endian int16 500 and -32768).
  m.data = {cblox::local_grid_t::FREE, cblox::local_grid_t::UNKNOWN, 0xF4, 0x01, 0x00, 0x80};
  m.raw_size = static_cast<int32_t>(m.data.size());
  m.num_bytes = m.raw_size;
  return m;
}

// One triangle with colours in block (seed, -1, 2) of subvolume 3 + seed.
inline cblox::mesh_block_t MakeMeshBlock(int seed) {
  cblox::mesh_block_t b{};
  b.subvolume_id = 3 + seed;
  b.index[0] = seed;
  b.index[1] = -1;
  b.index[2] = 2;
  b.num_vertices = 3;
  b.position = {{-100, 200, 300}, {32767, -32767, 0}, {static_cast<int16_t>(seed), 5, -6}};
  b.num_colors = 3;
  b.color = {{255, 0, 1}, {2, 254, 3}, {static_cast<uint8_t>(seed), 7, 8}};
  b.num_triangles = 1;
  b.triangle = {{0, 1, 2}};
  return b;
}

inline cblox::mesh_update_t MakeMeshUpdate() {
  cblox::mesh_update_t m{};
  m.utime = 1'700'000'000'000'020;
  m.map_epoch = 1'700'000'000'000'000;
  m.sequence = 42;
  m.refresh_start = true;
  m.blocks_pending = 17;
  m.block_size = 0.32f;
  m.num_removed = 2;
  m.removed_subvolume_ids = {1, 5};
  m.blocks = {MakeMeshBlock(1), MakeMeshBlock(2)};
  m.num_blocks = 2;
  return m;
}

inline cblox::subvolume_list_t MakeSubvolumeList() {
  cblox::subvolume_list_t m{};
  m.utime = 1'700'000'000'000'021;
  m.map_epoch = 1'700'000'000'000'000;
  m.active_subvolume_id = 4;
  m.block_size = 0.32f;
  m.num_subvolumes = 2;
  m.subvolume_ids = {3, 4};
  cblox::pose_t identity{};
  identity.orientation[0] = 1.0;
  m.poses = {MakePose(0.5), identity};
  m.anchor_keyframe_ids = {4294967296 + 10, 4294967296 + 20};
  m.num_blocks = {120, 7};
  m.bounds_min = {{-1.0f, -2.0f, 0.0f}, {0.32f, 0.0f, 0.0f}};
  m.bounds_max = {{3.2f, 1.28f, 2.56f}, {0.96f, 0.64f, 0.32f}};
  return m;
}

}  // namespace cblox::test
