// Round-trip tests for the generated cblox LCM types: every type is filled with
// distinctive non-default values, encoded, decoded into a fresh object, checked field by
// field and re-encoded (the bytes must be identical). Error paths: truncated buffers and
// buffers of another type (fingerprint mismatch) must fail to decode.
// Suite names start with "lcmtypes_" so `ctest -R lcm` selects them.

#include <gtest/gtest.h>
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
#include <cblox/pose_stamped_t.hpp>
#include <cblox/pose_t.hpp>
#include <cblox/stereo_pair_t.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "test/test_support/lcm_samples.h"

namespace {

using namespace cblox::test;  // the Make* sample-message builders

using Bytes = std::vector<uint8_t>;

// ---------------------------------------------------------------------------------------
// Generic helpers.

template <typename T>
Bytes Encode(const T& msg) {
  const int size = msg.getEncodedSize();
  EXPECT_GT(size, 8);  // at least the fingerprint plus something
  Bytes buf(static_cast<std::size_t>(size), 0xAB);
  const int written = msg.encode(buf.data(), 0, size);
  EXPECT_EQ(written, size);
  return buf;
}

// Encodes `msg`, decodes into a fresh object, checks the decode length, re-encodes the
// decoded object (bytes must match) and checks that every truncated prefix fails.
template <typename T>
T RoundTrip(const T& msg) {
  const Bytes encoded = Encode(msg);
  const int size = static_cast<int>(encoded.size());

  T decoded{};
  const int read = decoded.decode(encoded.data(), 0, size);
  EXPECT_EQ(read, size) << T::getTypeName();

  const Bytes reencoded = Encode(decoded);
  EXPECT_EQ(reencoded, encoded) << T::getTypeName() << ": re-encoding differs";

  // Decoding at a non-zero offset works too.
  Bytes shifted(3, 0x5A);
  shifted.insert(shifted.end(), encoded.begin(), encoded.end());
  T decoded_at_offset{};
  EXPECT_EQ(decoded_at_offset.decode(shifted.data(), 3, size), size) << T::getTypeName();
  EXPECT_EQ(Encode(decoded_at_offset), encoded) << T::getTypeName();

  // Every strict prefix of the buffer is a truncated message and must be rejected.
  for (int len = 0; len < size; ++len) {
    T truncated{};
    // Copy into an exactly sized buffer so a reader overrunning maxlen would be caught
    // by sanitizers.
    const Bytes prefix(encoded.begin(), encoded.begin() + len);
    EXPECT_LT(truncated.decode(prefix.data(), 0, len), 0)
        << T::getTypeName() << ": truncated to " << len << " of " << size << " bytes";
  }
  return decoded;
}

// ---------------------------------------------------------------------------------------
// Field-by-field comparisons (the sample messages come from test/test_support/lcm_samples.h).

void ExpectPoseEq(const cblox::pose_t& a, const cblox::pose_t& b) {
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.position[i], b.position[i]) << "position " << i;
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(a.orientation[i], b.orientation[i]) << "orientation " << i;
  }
}

void ExpectCalibrationEq(const cblox::camera_calibration_t& a,
                         const cblox::camera_calibration_t& b) {
  EXPECT_EQ(a.camera_id, b.camera_id);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.fx, b.fx);
  EXPECT_EQ(a.fy, b.fy);
  EXPECT_EQ(a.cx, b.cx);
  EXPECT_EQ(a.cy, b.cy);
  EXPECT_EQ(a.distortion_model, b.distortion_model);
  EXPECT_EQ(a.num_distortion, b.num_distortion);
  EXPECT_EQ(a.distortion, b.distortion);
  ExpectPoseEq(a.T_B_C, b.T_B_C);
}

void ExpectImageEq(const cblox::image_t& a, const cblox::image_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.camera_id, b.camera_id);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.row_stride, b.row_stride);
  EXPECT_EQ(a.pixel_format, b.pixel_format);
  EXPECT_EQ(a.depth_scale, b.depth_scale);
  EXPECT_EQ(a.size, b.size);
  EXPECT_EQ(a.data, b.data);
}

// ---------------------------------------------------------------------------------------
// One test per type.

TEST(lcmtypes_roundtrip, PoseT) {
  const cblox::pose_t m = MakePose(0.75);
  const cblox::pose_t d = RoundTrip(m);
  ExpectPoseEq(d, m);
  EXPECT_EQ(d.position[2], 3.75 * 1.75);
  EXPECT_EQ(d.orientation[0], 1.25);
}

TEST(lcmtypes_roundtrip, PoseStampedT) {
  const cblox::pose_stamped_t m = MakePoseStamped();
  const cblox::pose_stamped_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, 1'700'000'000'000'001);
  EXPECT_EQ(d.frame_id, 4242);
  EXPECT_EQ(d.frame, "G");
  ExpectPoseEq(d.T_G_C, m.T_G_C);
}

TEST(lcmtypes_roundtrip, CameraCalibrationT) {
  const cblox::camera_calibration_t m = MakeCalibration("cam7", 0.5);
  const cblox::camera_calibration_t d = RoundTrip(m);
  ExpectCalibrationEq(d, m);
  EXPECT_EQ(d.camera_id, "cam7");
  EXPECT_EQ(d.distortion_model, "radtan");
  ASSERT_EQ(d.distortion.size(), 4U);
  EXPECT_EQ(d.distortion[0], -0.28340811);
  EXPECT_EQ(d.num_distortion, 4);
}

TEST(lcmtypes_roundtrip, ImageT) {
  const cblox::image_t m = MakeImage("cam0", cblox::image_t::DEPTH_F32, 6, 5, 4, 17);
  const cblox::image_t d = RoundTrip(m);
  ExpectImageEq(d, m);
  EXPECT_EQ(d.pixel_format, cblox::image_t::DEPTH_F32);
  EXPECT_EQ(d.size, (6 * 4 + 2) * 5);
  ASSERT_EQ(d.data.size(), static_cast<std::size_t>(d.size));
  EXPECT_EQ(d.data[0], 17);
  EXPECT_EQ(d.data[10], static_cast<uint8_t>(10 * 7 + 17));
}

TEST(lcmtypes_roundtrip, ImageTPixelFormatConstantsAreDistinct) {
  const std::set<int8_t> formats = {cblox::image_t::GRAY8,     cblox::image_t::RGB8,
                                    cblox::image_t::BGR8,      cblox::image_t::RGBA8,
                                    cblox::image_t::DEPTH_U16, cblox::image_t::DEPTH_F32};
  EXPECT_EQ(formats.size(), 6U);
}

TEST(lcmtypes_roundtrip, StereoPairT) {
  const cblox::stereo_pair_t m = MakeStereoPair();
  const cblox::stereo_pair_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.frame_id, 77);
  ExpectImageEq(d.left, m.left);
  ExpectImageEq(d.right, m.right);
  EXPECT_EQ(d.right.pixel_format, cblox::image_t::RGB8);
  ExpectCalibrationEq(d.left_calibration, m.left_calibration);
  ExpectCalibrationEq(d.right_calibration, m.right_calibration);
  EXPECT_EQ(d.right_calibration.camera_id, "cam1");
  ExpectPoseEq(d.T_L_R, m.T_L_R);
  EXPECT_EQ(d.rectified, 1);
}

TEST(lcmtypes_roundtrip, DepthFrameT) {
  const cblox::depth_frame_t m = MakeDepthFrame();
  const cblox::depth_frame_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.frame_id, 78);
  ExpectImageEq(d.depth, m.depth);
  EXPECT_EQ(d.depth.pixel_format, cblox::image_t::DEPTH_U16);
  EXPECT_EQ(d.depth.depth_scale, 0.001);
  EXPECT_EQ(d.has_color, 1);
  ExpectImageEq(d.color, m.color);
  ExpectCalibrationEq(d.calibration, m.calibration);
  EXPECT_EQ(d.min_depth_m, 0.3F);
  EXPECT_EQ(d.max_depth_m, 4.5F);
}

TEST(lcmtypes_roundtrip, DepthFrameTWithoutColor) {
  cblox::depth_frame_t m = MakeDepthFrame();
  m.has_color = 0;
  m.color = cblox::image_t{};  // empty image: size 0, no data
  const cblox::depth_frame_t d = RoundTrip(m);
  EXPECT_EQ(d.has_color, 0);
  EXPECT_EQ(d.color.size, 0);
  EXPECT_TRUE(d.color.data.empty());
  ExpectImageEq(d.depth, m.depth);
}

TEST(lcmtypes_roundtrip, FramePoseT) {
  const cblox::frame_pose_t m = MakeFramePose();
  const cblox::frame_pose_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.frame_id, 79);
  ExpectPoseEq(d.T_G_C, m.T_G_C);
  EXPECT_EQ(d.tracking_state, cblox::frame_pose_t::LOOP_CORRECTED);
  EXPECT_EQ(d.tracking_jump, 1);
  EXPECT_EQ(d.map_epoch, 3);
  EXPECT_EQ(d.reference_keyframe_id, 4321);
  const std::set<int8_t> states = {cblox::frame_pose_t::NOT_INITIALIZED,
                                   cblox::frame_pose_t::OK,
                                   cblox::frame_pose_t::LOST,
                                   cblox::frame_pose_t::RELOCALIZED,
                                   cblox::frame_pose_t::LOOP_CORRECTED,
                                   cblox::frame_pose_t::MAP_RESET};
  EXPECT_EQ(states.size(), 6U);
}

TEST(lcmtypes_roundtrip, KeyframeT) {
  const cblox::keyframe_t m = MakeKeyframe();
  const cblox::keyframe_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.keyframe_id, 12);
  EXPECT_EQ(d.frame_id, 80);
  ExpectPoseEq(d.T_G_K, m.T_G_K);
  EXPECT_EQ(d.num_landmarks, 4);
  EXPECT_EQ(d.landmark_ids, (std::vector<int64_t>{5, 1'000'000'000'007, -3, 99}));
}

TEST(lcmtypes_roundtrip, KeyframePoseBatchT) {
  const cblox::keyframe_pose_batch_t m = MakeKeyframePoseBatch();
  const cblox::keyframe_pose_batch_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.reason, cblox::keyframe_pose_batch_t::GLOBAL_BA);
  EXPECT_EQ(d.num_keyframes, 3);
  EXPECT_EQ(d.keyframe_ids, (std::vector<int64_t>{12, 13, 21}));
  ASSERT_EQ(d.poses.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) ExpectPoseEq(d.poses[i], m.poses[i]);
  EXPECT_EQ(d.poses[2].position[0], 1.25 + 7.0);
  const std::set<int8_t> reasons = {
      cblox::keyframe_pose_batch_t::LOCAL_BA, cblox::keyframe_pose_batch_t::LOOP_CORRECTION,
      cblox::keyframe_pose_batch_t::GLOBAL_BA, cblox::keyframe_pose_batch_t::RELOCALIZATION};
  EXPECT_EQ(reasons.size(), 4U);
}

TEST(lcmtypes_roundtrip, CovarianceRequestT) {
  const cblox::covariance_request_t m = MakeCovarianceRequest();
  const cblox::covariance_request_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.request_id, 901);
  EXPECT_EQ(d.num_pairs, 2);
  EXPECT_EQ(d.keyframe_i, (std::vector<int64_t>{12, 13}));
  EXPECT_EQ(d.keyframe_j, (std::vector<int64_t>{40, 41}));
}

TEST(lcmtypes_roundtrip, DistanceRequestT) {
  const cblox::distance_request_t m = MakeDistanceRequest();
  const cblox::distance_request_t d = RoundTrip(m);
  EXPECT_EQ(d.request_id, m.request_id);
  EXPECT_EQ(d.map_epoch, m.map_epoch);
  ASSERT_EQ(d.num_points, 3);
  ASSERT_EQ(d.points.size(), 3U);
  EXPECT_EQ(d.points[0], (std::vector<double>{0.5, -1.25, 0.75}));
  EXPECT_EQ(d.points[2], (std::vector<double>{-3.5, 4.0, 0.25}));
  // 8 fingerprint + 3 x 8 + 4 + 3 x 3 x 8 bytes.
  EXPECT_EQ(m.getEncodedSize(), 8 + 24 + 4 + 72);
  EXPECT_EQ(cblox::distance_request_t::MAX_POINTS, 4096);
}

TEST(lcmtypes_roundtrip, DistanceReplyT) {
  const cblox::distance_reply_t m = MakeDistanceReply();
  const cblox::distance_reply_t d = RoundTrip(m);
  EXPECT_EQ(d.request_id, m.request_id);
  EXPECT_EQ(d.status, cblox::distance_reply_t::STATUS_OK);
  EXPECT_EQ(d.max_distance_m, 2.0f);
  ASSERT_EQ(d.num_points, 3);
  EXPECT_EQ(d.state, (std::vector<int8_t>{1, 2, 0}));
  EXPECT_EQ(d.distance, (std::vector<float>{0.625f, -0.03125f, 0.0f}));
  EXPECT_EQ(d.gradient[1], (std::vector<float>{1.0f, 0.0f, 0.0f}));
}

TEST(lcmtypes_roundtrip, LocalGridT) {
  const cblox::local_grid_t m = MakeLocalGrid();
  const cblox::local_grid_t d = RoundTrip(m);
  EXPECT_EQ(d.origin[2], -0.5);
  EXPECT_EQ(d.resolution, 0.25);
  EXPECT_EQ(d.size[0], 2);
  EXPECT_EQ(d.encoding, cblox::local_grid_t::ENCODING_RAW);
  EXPECT_EQ(d.raw_size, 6);
  EXPECT_EQ(d.data, m.data);
}

TEST(lcmtypes_roundtrip, MeshUpdateT) {
  const cblox::mesh_update_t m = MakeMeshUpdate();
  const cblox::mesh_update_t d = RoundTrip(m);
  EXPECT_EQ(d.sequence, 42);
  EXPECT_TRUE(d.refresh_start);
  EXPECT_EQ(d.blocks_pending, 17);
  EXPECT_EQ(d.block_size, 0.32f);
  EXPECT_EQ(d.removed_subvolume_ids, (std::vector<int64_t>{1, 5}));
  ASSERT_EQ(d.num_blocks, 2);
  EXPECT_EQ(d.blocks[1].subvolume_id, 5);
  EXPECT_EQ(d.blocks[1].index[0], 2);
  EXPECT_EQ(d.blocks[1].position[1], (std::vector<int16_t>{32767, -32767, 0}));
  EXPECT_EQ(d.blocks[1].color[2], (std::vector<uint8_t>{2, 7, 8}));
  EXPECT_EQ(d.blocks[0].triangle[0], (std::vector<int16_t>{0, 1, 2}));
}

TEST(lcmtypes_roundtrip, SubvolumeListT) {
  const cblox::subvolume_list_t m = MakeSubvolumeList();
  const cblox::subvolume_list_t d = RoundTrip(m);
  EXPECT_EQ(d.active_subvolume_id, 4);
  EXPECT_EQ(d.subvolume_ids, (std::vector<int64_t>{3, 4}));
  EXPECT_EQ(d.poses[0].position[0], m.poses[0].position[0]);
  EXPECT_EQ(d.anchor_keyframe_ids[1], 4294967296 + 20);
  EXPECT_EQ(d.num_blocks, (std::vector<int32_t>{120, 7}));
  EXPECT_EQ(d.bounds_max[0], (std::vector<float>{3.2f, 1.28f, 2.56f}));
}

TEST(lcmtypes_roundtrip, CovariancePairT) {
  const cblox::covariance_pair_t m = MakeCovariancePair(5, 6, false);
  const cblox::covariance_pair_t d = RoundTrip(m);
  EXPECT_EQ(d.keyframe_i, 5);
  EXPECT_EQ(d.keyframe_j, 6);
  EXPECT_EQ(d.ok, 0);
  EXPECT_EQ(d.error, "keyframe not in graph");
  for (int k = 0; k < 36; ++k) EXPECT_EQ(d.sigma_i_given_j[k], m.sigma_i_given_j[k]) << k;
  EXPECT_EQ(d.sigma_i_given_j[35], 0.001 * 36 + 5.0);
  EXPECT_EQ(d.q, 0.0375 * 6.0);
}

TEST(lcmtypes_roundtrip, CovarianceReplyT) {
  const cblox::covariance_reply_t m = MakeCovarianceReply();
  const cblox::covariance_reply_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.request_id, 901);
  EXPECT_EQ(d.num_pairs, 2);
  ASSERT_EQ(d.pairs.size(), 2U);
  EXPECT_EQ(d.pairs[0].keyframe_i, 12);
  EXPECT_EQ(d.pairs[0].keyframe_j, 40);
  EXPECT_EQ(d.pairs[0].ok, 1);
  EXPECT_EQ(d.pairs[0].error, "");
  EXPECT_EQ(d.pairs[1].ok, 0);
  EXPECT_EQ(d.pairs[1].error, "keyframe not in graph");
  for (int k = 0; k < 36; ++k) {
    EXPECT_EQ(d.pairs[1].sigma_i_given_j[k], m.pairs[1].sigma_i_given_j[k]) << k;
  }
  EXPECT_EQ(d.pairs[1].q, m.pairs[1].q);
}

TEST(lcmtypes_roundtrip, CommandT) {
  const cblox::command_t m = MakeCommand();
  const cblox::command_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.command_id, 31337);
  EXPECT_EQ(d.sender, "cblox-ctl");
  EXPECT_EQ(d.name, "export_mesh");
  EXPECT_EQ(d.num_args, 2);
  EXPECT_EQ(d.arg_keys, (std::vector<std::string>{"path", "voxel_size"}));
  EXPECT_EQ(d.arg_values, (std::vector<std::string>{"/tmp/mesh.ply", "0.05"}));
}

TEST(lcmtypes_roundtrip, CommandReplyT) {
  const cblox::command_reply_t m = MakeCommandReply();
  const cblox::command_reply_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.command_id, 31337);
  EXPECT_EQ(d.ok, 1);
  EXPECT_EQ(d.message, "mesh written");
  EXPECT_EQ(d.num_values, 3);
  EXPECT_EQ(d.value_keys, (std::vector<std::string>{"path", "num_triangles", "empty"}));
  EXPECT_EQ(d.values, (std::vector<std::string>{"/tmp/mesh.ply", "12345", ""}));
}

TEST(lcmtypes_roundtrip, MapStatusT) {
  const cblox::map_status_t m = MakeMapStatus();
  const cblox::map_status_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.num_subvolumes, 17);
  EXPECT_EQ(d.active_subvolume_id, 16);
  EXPECT_EQ(d.num_blocks, 123'456);
  EXPECT_EQ(d.memory_bytes, 5'000'000'123);
  EXPECT_EQ(d.frames_received, 1001);
  EXPECT_EQ(d.frames_integrated, 950);
  EXPECT_EQ(d.frames_dropped, 40);
  EXPECT_EQ(d.frames_rejected, 11);
  EXPECT_EQ(d.integration_ms_last, 12.5F);
  EXPECT_EQ(d.integration_ms_median, 10.25F);
  EXPECT_EQ(d.integration_ms_p99, 31.75F);
  EXPECT_EQ(d.fusion_candidates, 9);
  EXPECT_EQ(d.covariance_requested, 8);
  EXPECT_EQ(d.subvolumes_fused, 5);
  EXPECT_EQ(d.rejected_by_q, 2);
}

TEST(lcmtypes_roundtrip, HeartbeatT) {
  const cblox::heartbeat_t m = MakeHeartbeat();
  const cblox::heartbeat_t d = RoundTrip(m);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.process, "cblox-mapper");
  EXPECT_EQ(d.pid, 4711);
  EXPECT_EQ(d.state, "running");
  EXPECT_EQ(d.num_counters, 2);
  EXPECT_EQ(d.counter_names, (std::vector<std::string>{"frames_in", "frames_out"}));
  EXPECT_EQ(d.counter_values, (std::vector<int64_t>{1'000'000'000'000, -1}));
}

// ---------------------------------------------------------------------------------------
// Error paths.

TEST(lcmtypes_errors, TruncatedBufferFails) {
  const Bytes encoded = Encode(MakeStereoPair());
  const int size = static_cast<int>(encoded.size());
  cblox::stereo_pair_t d{};
  EXPECT_LT(d.decode(encoded.data(), 0, size - 1), 0);
  EXPECT_LT(d.decode(encoded.data(), 0, size / 2), 0);
  EXPECT_LT(d.decode(encoded.data(), 0, 8), 0);  // fingerprint only
  EXPECT_LT(d.decode(encoded.data(), 0, 0), 0);
  // The full buffer still decodes after the failures above.
  EXPECT_EQ(d.decode(encoded.data(), 0, size), size);
}

// A set of encoders and decoders, one per type, to check every pair of types.
struct TypeOps {
  std::string name;
  int64_t hash;
  Bytes encoded;
  std::function<int(const Bytes&)> decode;
};

template <typename T>
TypeOps MakeOps(const T& msg) {
  return TypeOps{T::getTypeName(), T::getHash(), Encode(msg), [](const Bytes& buf) {
                   T out{};
                   return out.decode(buf.data(), 0, static_cast<int>(buf.size()));
                 }};
}

std::vector<TypeOps> AllTypes() {
  return {MakeOps(MakePose(0.0)),
          MakeOps(MakePoseStamped()),
          MakeOps(MakeCalibration("cam0", 0.0)),
          MakeOps(MakeImage("cam0", cblox::image_t::GRAY8, 4, 4, 1, 1)),
          MakeOps(MakeStereoPair()),
          MakeOps(MakeDepthFrame()),
          MakeOps(MakeFramePose()),
          MakeOps(MakeKeyframe()),
          MakeOps(MakeKeyframePoseBatch()),
          MakeOps(MakeCovarianceRequest()),
          MakeOps(MakeCovariancePair(1, 2, true)),
          MakeOps(MakeCovarianceReply()),
          MakeOps(MakeCommand()),
          MakeOps(MakeCommandReply()),
          MakeOps(MakeMapStatus()),
          MakeOps(MakeHeartbeat()),
          MakeOps(MakeDistanceRequest()),
          MakeOps(MakeDistanceReply()),
          MakeOps(MakeLocalGrid()),
          MakeOps(MakeMeshBlock(1)),
          MakeOps(MakeMeshUpdate()),
          MakeOps(MakeSubvolumeList())};
}

TEST(lcmtypes_errors, FingerprintsAreUnique) {
  const std::vector<TypeOps> types = AllTypes();
  ASSERT_EQ(types.size(), 22U);
  std::set<int64_t> hashes;
  for (const TypeOps& t : types) hashes.insert(t.hash);
  EXPECT_EQ(hashes.size(), types.size());
}

TEST(lcmtypes_errors, DecodingAsAnotherTypeFailsOnFingerprint) {
  const std::vector<TypeOps> types = AllTypes();
  for (const TypeOps& from : types) {
    for (const TypeOps& as : types) {
      const int rc = as.decode(from.encoded);
      if (from.name == as.name) {
        EXPECT_EQ(rc, static_cast<int>(from.encoded.size())) << from.name;
      } else {
        // The generated decoder checks the 8-byte fingerprint first and returns -1.
        EXPECT_EQ(rc, -1) << from.name << " decoded as " << as.name;
      }
    }
  }
}

TEST(lcmtypes_errors, ExplicitMismatchStereoAsDepth) {
  const Bytes stereo = Encode(MakeStereoPair());
  cblox::depth_frame_t d{};
  EXPECT_LT(d.decode(stereo.data(), 0, static_cast<int>(stereo.size())), 0);
  const Bytes pose = Encode(MakePose(1.0));
  cblox::pose_stamped_t ps{};
  EXPECT_LT(ps.decode(pose.data(), 0, static_cast<int>(pose.size())), 0);
}

}  // namespace
