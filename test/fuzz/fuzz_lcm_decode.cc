// Fuzz target: any bytes as a message of every LCM type (lcmtypes/*.lcm) through the wire
// check and decode the message guard uses (decodeChecked, lcmtypes/wire_check.h), then the
// conversions the daemons apply to what decoded (daemon/common/lcm_messages.h,
// daemon/common/mesh_stream_codec.h and a MeshMirror for the mesh stream).

#include <cstddef>
#include <cstdint>
#include <string>

#include <cblox/wire_schema.hpp>

#include "core/mapping/mesh_mirror.h"
#include "daemon/common/lcm_messages.h"
#include "daemon/common/mesh_stream_codec.h"
#include "lcmtypes/wire_check.h"

#include <cblox/camera_calibration_t.hpp>
#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/covariance_pair_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/distance_reply_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/local_grid_t.hpp>
#include <cblox/mesh_block_t.hpp>
#include <cblox/mesh_update_t.hpp>
#include <cblox/subvolume_list_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/map_status_t.hpp>

namespace cblox {
namespace {

void convertImage(const image_t& msg) {
  std::string error;
  GrayImage gray;
  ColorImage color;
  DepthImage depth;
  (void)fromImageMsg(msg, &gray, &error);
  (void)fromImageMsg(msg, &color, &error);
  (void)fromDepthImageMsg(msg, &depth, &error);
}

void convertCalibration(const camera_calibration_t& msg) {
  std::string error;
  (void)fromCalibrationMsg(msg, &error);
  (void)fromPoseMsg(msg.T_B_C, &error);
}

// What the daemons do with each type after decoding it (nothing for the outputs they only
// print or count).
template <typename Msg>
void convert(const Msg&) {}
template <>
void convert(const pose_t& msg) {
  std::string error;
  (void)fromPoseMsg(msg, &error);
}
template <>
void convert(const image_t& msg) {
  convertImage(msg);
}
template <>
void convert(const camera_calibration_t& msg) {
  convertCalibration(msg);
}
template <>
void convert(const stereo_pair_t& msg) {
  std::string error;
  (void)fromStereoCalibrationMsg(msg, &error);
  convertImage(msg.left);
  convertImage(msg.right);
}
template <>
void convert(const depth_frame_t& msg) {
  convertImage(msg.depth);
  convertImage(msg.color);
  convertCalibration(msg.calibration);
}
template <>
void convert(const pose_stamped_t& msg) {
  convert(msg.T_G_C);
}
template <>
void convert(const frame_pose_t& msg) {
  convert(msg.T_G_C);
}
template <>
void convert(const keyframe_t& msg) {
  convert(msg.T_G_K);
}
template <>
void convert(const keyframe_pose_batch_t& msg) {
  for (const pose_t& pose : msg.poses) convert(pose);
}

template <>
void convert(const mesh_update_t& msg) {
  std::string error;
  MeshUpdate update;
  if (!decodeMeshUpdate(msg, &update, &error)) return;
  MeshMirror mirror;
  (void)mirror.apply(update);
  (void)mirror.meshInG();
}
template <>
void convert(const subvolume_list_t& msg) {
  std::string error;
  SubvolumeList list;
  if (!decodeSubvolumeList(msg, &list, &error)) return;
  MeshMirror mirror;
  mirror.applySubvolumes(list);
  (void)mirror.meshInG();
}

template <typename Msg>
void decodeAs(const uint8_t* data, size_t size) {
  Msg msg;
  if (decodeChecked(data, size, &msg).ok()) convert(msg);
}

}  // namespace
}  // namespace cblox

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
#define CBLOX_FUZZ_DECODE(type) cblox::decodeAs<cblox::type>(data, size);
  CBLOX_WIRE_SCHEMA_FOR_EACH_TYPE(CBLOX_FUZZ_DECODE)
#undef CBLOX_FUZZ_DECODE
  return 0;
}
