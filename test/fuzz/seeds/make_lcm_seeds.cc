// Writes the LCM seed corpora of the fuzz targets (test/fuzz/corpus/): small valid messages of
// every type, encoded as the daemons publish them (daemon/common/lcm_messages.h), a few
// corrupt copies, and for the node targets the same with the channel-choosing first byte
// (fuzz_mapper_lcm.cc, fuzz_tracker_lcm.cc). Run by hand after a message type changes:
//   build/test/fuzz/make_lcm_seeds test/fuzz/corpus

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <cblox/command_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/map_status_t.hpp>

#include "daemon/common/heartbeat.h"
#include "test/test_support/lcm_samples.h"
#include "daemon/common/lcm_messages.h"

namespace cblox {
namespace {

using Bytes = std::vector<uint8_t>;
constexpr int kWidth = 16, kHeight = 12;

template <typename Msg>
Bytes encode(const Msg& msg) {
  Bytes bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

void write(const std::filesystem::path& path, const Bytes& bytes, uint8_t prefix = 0,
           bool with_prefix = false) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  if (with_prefix) out.put(static_cast<char>(prefix));
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

PinholeIntrinsics intrinsics() {
  PinholeIntrinsics in;
  in.fx = in.fy = 12.0;
  in.cx = 7.5;
  in.cy = 5.5;
  in.width = kWidth;
  in.height = kHeight;
  return in;
}

Transformationd pose(double x) {
  return Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * x, Eigen::Vector3d::UnitY())),
                         Eigen::Vector3d(x, 0.0, 0.0));
}

GrayImage gray(int shift) {
  GrayImage image(kWidth, kHeight);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u)
      image(u, v) = static_cast<uint8_t>(((u + shift) / 4 + v / 4) % 2 * 200);
  }
  return image;
}

depth_frame_t depthFrame(int64_t utime, int64_t frame_id, DepthEncoding encoding) {
  depth_frame_t msg;
  msg.utime = utime;
  msg.frame_id = frame_id;
  DepthImage depth(kWidth, kHeight, 1.5f);
  depth(3, 4) = 0.0f;  // an invalid reading
  msg.depth = toDepthImageMsg(depth, utime, "depth", encoding);
  msg.has_color = true;
  msg.color = toImageMsg(ColorImage(kWidth, kHeight, Color{200, 100, 50}), utime, "depth");
  msg.calibration = toCalibrationMsg("depth", intrinsics(), Transformationd());
  msg.min_depth_m = 0.1f;
  msg.max_depth_m = 5.0f;
  return msg;
}

stereo_pair_t stereoPair(int64_t utime, int64_t frame_id) {
  stereo_pair_t msg;
  msg.utime = utime;
  msg.frame_id = frame_id;
  msg.left = toImageMsg(gray(0), utime, "left");
  msg.right = toImageMsg(gray(2), utime, "right");
  msg.left_calibration = toCalibrationMsg("left", intrinsics(), Transformationd());
  msg.right_calibration = toCalibrationMsg(
      "right", intrinsics(), Transformationd(Eigen::Quaterniond::Identity(), {0.1, 0, 0}));
  msg.T_L_R = toPoseMsg(Transformationd(Eigen::Quaterniond::Identity(), {0.1, 0, 0}));
  msg.rectified = true;
  return msg;
}

pose_stamped_t groundTruth(int64_t utime, int64_t frame_id) {
  pose_stamped_t msg;
  msg.utime = utime;
  msg.frame_id = frame_id;
  msg.frame = "world";
  msg.T_G_C = toPoseMsg(pose(0.01 * static_cast<double>(frame_id)));
  return msg;
}

command_t command(const std::string& name, std::vector<std::pair<std::string, std::string>> args) {
  command_t msg;
  msg.utime = 1;
  msg.command_id = 7;
  msg.sender = "fuzz";
  msg.name = name;
  for (const auto& [key, value] : args) {
    msg.arg_keys.push_back(key);
    msg.arg_values.push_back(value);
  }
  msg.num_args = static_cast<int32_t>(msg.arg_keys.size());
  return msg;
}

covariance_request_t covarianceRequest() {
  covariance_request_t msg;
  msg.utime = 1;
  msg.request_id = 3;
  msg.keyframe_i = {1, 2};
  msg.keyframe_j = {0, 0};
  msg.num_pairs = 2;
  return msg;
}

covariance_reply_t covarianceReply() {
  covariance_reply_t msg;
  msg.utime = 1;
  msg.request_id = 1;
  covariance_pair_t pair;
  pair.keyframe_i = 1;
  pair.keyframe_j = 0;
  pair.ok = true;
  pair.error = "";
  for (int i = 0; i < 36; ++i) pair.sigma_i_given_j[i] = i % 7 == 0 ? 1e-4 : 0.0;
  pair.q = 1e4;
  msg.pairs = {pair, pair};
  msg.pairs[1].ok = false;
  msg.pairs[1].error = "unknown keyframe";
  msg.num_pairs = 2;
  return msg;
}

Bytes truncated(Bytes bytes) {
  bytes.resize(bytes.size() / 2);
  return bytes;
}

// Sets a 4-byte big-endian count at `offset` to -1 (a corrupt length).
Bytes corruptCount(Bytes bytes, size_t offset) {
  for (size_t i = 0; i < 4 && offset + i < bytes.size(); ++i) bytes[offset + i] = 0xff;
  return bytes;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  using namespace cblox;
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_lcm_seeds CORPUS_DIR (test/fuzz/corpus)\n");
    return 2;
  }
  const std::filesystem::path root(argv[1]);
  const Bytes depth_u16 = encode(depthFrame(1000000, 1, DepthEncoding::kUint16Millimetres));
  const Bytes depth_f32 = encode(depthFrame(1100000, 2, DepthEncoding::kFloat32Metres));
  const Bytes stereo = encode(stereoPair(1000000, 1));
  const Bytes gt = encode(groundTruth(1000000, 1));
  const Bytes frame_pose =
      encode(toFramePoseMsg(1000000, 1, pose(0.0), frame_pose_t::OK, false, 0, 0));
  const Bytes frame_lost =
      encode(toFramePoseMsg(1100000, 2, std::nullopt, frame_pose_t::LOST, false, 0));
  const Bytes keyframe = encode(toKeyframeMsg(1000000, 0, 1, pose(0.0), {1, 2, 3, 5, 8}, 0));
  const Bytes keyframe_poses = encode(toKeyframePoseBatchMsg(
      2000000, keyframe_pose_batch_t::LOCAL_BA, {{0, pose(0.1)}, {1, pose(0.2)}}, 0));
  const Bytes status = encode(command("status", {}));
  const Bytes export_mesh = encode(command("export_mesh", {{"path", "mesh.ply"}}));
  const Bytes save_map = encode(command("save_map", {{"path", "map"}}));
  const Bytes load_map = encode(command("load_map", {{"path", "map"}}));
  const Bytes submaps = encode(command("export_submap_meshes", {{"path", "submaps"}}));
  const Bytes cov_request = encode(covarianceRequest());
  const Bytes cov_reply = encode(covarianceReply());
  const Bytes heartbeat =
      encode(HeartbeatBuilder("cblox-tracker", "ok").add("frames", uint64_t{3}).build());
  map_status_t map_status;
  map_status.num_subvolumes = 2;
  const Bytes distance_request =
      encode(test::MakeDistanceRequest(1, 0, {{0.5, 0.25, 1.0}, {1.0, 2.0, 0.5}, {0.0, 0.0, 0.0}}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Bytes distance_hostile = encode(
      test::MakeDistanceRequest(2, 77, {{nan, 0.0, 1.0}, {inf, -inf, 0.0}, {1e6, -1e6, 1e6}, {0.1, 0.1, 0.1}}));

  // Every type, valid and corrupt.
  const std::filesystem::path decode = root / "fuzz_lcm_decode";
  write(decode / "depth_frame_u16", depth_u16);
  write(decode / "depth_frame_f32", depth_f32);
  write(decode / "stereo_pair", stereo);
  write(decode / "pose_stamped", gt);
  write(decode / "frame_pose", frame_pose);
  write(decode / "keyframe", keyframe);
  write(decode / "keyframe_pose_batch", keyframe_poses);
  write(decode / "command", export_mesh);
  write(decode / "covariance_request", cov_request);
  write(decode / "covariance_reply", cov_reply);
  write(decode / "heartbeat", heartbeat);
  write(decode / "map_status", encode(map_status));
  write(decode / "image", encode(toImageMsg(gray(1), 5, "left")));
  write(decode / "camera_calibration", encode(toCalibrationMsg("c", intrinsics(), pose(1.0))));
  write(decode / "pose", encode(toPoseMsg(pose(2.0))));
  write(decode / "distance_request", distance_request);
  write(decode / "mesh_update", encode(test::MakeMeshUpdate()));
  write(decode / "subvolume_list", encode(test::MakeSubvolumeList()));
  write(decode / "invalid_truncated_stereo_pair", truncated(stereo));
  write(decode / "invalid_count_keyframe", corruptCount(keyframe, keyframe.size() - 5 * 8 - 4));

  // The mapper: first byte = pose source (0x80 tracker) | channel index (fuzz_mapper_lcm.cc:
  // depth, keyframe poses, command, heartbeat, then ground truth | frame pose, keyframe,
  // covariance reply, then distance request).
  const std::filesystem::path mapper = root / "fuzz_mapper_lcm";
  write(mapper / "gt_depth_u16", depth_u16, 0x00, true);
  write(mapper / "gt_depth_f32", depth_f32, 0x00, true);
  write(mapper / "gt_pose", gt, 0x04, true);
  write(mapper / "gt_keyframe_poses", keyframe_poses, 0x01, true);
  write(mapper / "gt_status", status, 0x02, true);
  write(mapper / "gt_export_mesh", export_mesh, 0x02, true);
  write(mapper / "gt_save_map", save_map, 0x02, true);
  write(mapper / "gt_load_map", load_map, 0x02, true);
  write(mapper / "gt_export_submaps", submaps, 0x02, true);
  write(mapper / "gt_heartbeat", heartbeat, 0x03, true);
  write(mapper / "tracker_depth", depth_u16, 0x80, true);
  write(mapper / "tracker_frame_pose", frame_pose, 0x84, true);
  write(mapper / "tracker_frame_lost", frame_lost, 0x84, true);
  write(mapper / "tracker_keyframe", keyframe, 0x85, true);
  write(mapper / "tracker_keyframe_poses", keyframe_poses, 0x81, true);
  write(mapper / "tracker_covariance_reply", cov_reply, 0x86, true);
  write(mapper / "gt_distance_request", distance_request, 0x05, true);
  write(mapper / "tracker_distance_request", distance_request, 0x87, true);
  write(mapper / "tracker_distance_hostile", distance_hostile, 0x87, true);
  // num_points (after the fingerprint, utime, request_id and map_epoch) forged to -1.
  write(mapper / "invalid_tracker_distance_count", corruptCount(distance_request, 8 + 3 * 8),
        0x87, true);
  write(mapper / "invalid_gt_depth_truncated", truncated(depth_u16), 0x00, true);
  write(mapper / "invalid_tracker_keyframe_count",
        corruptCount(keyframe, keyframe.size() - 5 * 8 - 4), 0x85, true);

  // The tracker: first byte = mode (0x80 RGB-D with ground-truth initial pose) | channel index
  // (fuzz_tracker_lcm.cc: frames, covariance request, heartbeat, then ground truth).
  const std::filesystem::path tracker = root / "fuzz_tracker_lcm";
  write(tracker / "stereo_frame", stereo, 0x00, true);
  write(tracker / "stereo_covariance_request", cov_request, 0x01, true);
  write(tracker / "stereo_heartbeat", heartbeat, 0x02, true);
  write(tracker / "rgbd_depth_u16", depth_u16, 0x80, true);
  write(tracker / "rgbd_depth_f32", depth_f32, 0x80, true);
  write(tracker / "rgbd_ground_truth", gt, 0x83, true);
  write(tracker / "rgbd_covariance_request", cov_request, 0x81, true);
  write(tracker / "invalid_stereo_truncated", truncated(stereo), 0x00, true);
  std::printf("LCM seeds written under %s\n", root.c_str());
  return 0;
}
