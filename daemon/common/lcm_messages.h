#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <cblox/camera_calibration_t.hpp>
#include <cblox/depth_frame_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/image_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/pose_t.hpp>
#include <cblox/stereo_pair_t.hpp>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/geometry/stereo_rig.h"
#include "drivers/frame_source.h"

namespace cblox {

/// Conversions between core types and the LCM messages of lcmtypes/. All functions are
/// thread-safe (pure). Decoders validate every field and return false / std::nullopt with a
/// message naming the field, never crash on a malformed message.

/// How depth images travel: 16-bit millimetres (like a depth sensor: half the bytes, 1 mm
/// steps, 65.535 m max) or 32-bit float metres (exact).
enum class DepthEncoding { kUint16Millimetres, kFloat32Metres };

pose_t toPoseMsg(const Transformationd& T);
/// Fails on non-finite values or a quaternion whose norm is not within 1e-3 of 1.
std::optional<Transformationd> fromPoseMsg(const pose_t& msg, std::string* error);

camera_calibration_t toCalibrationMsg(const std::string& camera_id,
                                      const PinholeIntrinsics& intrinsics,
                                      const Transformationd& T_B_C);
/// Accepts only distortion model "none" (rectified / registered images).
std::optional<PinholeIntrinsics> fromCalibrationMsg(const camera_calibration_t& msg,
                                                    std::string* error);

image_t toImageMsg(const GrayImage& image, int64_t utime, const std::string& camera_id);
image_t toImageMsg(const ColorImage& image, int64_t utime, const std::string& camera_id);
image_t toDepthImageMsg(const DepthImage& depth, int64_t utime, const std::string& camera_id,
                        DepthEncoding encoding);

/// GRAY8 images (RGB8/BGR8/RGBA8 are converted to grey with BT.601 weights).
bool fromImageMsg(const image_t& msg, GrayImage* image, std::string* error);
/// RGB8, BGR8, RGBA8 or GRAY8 images.
bool fromImageMsg(const image_t& msg, ColorImage* image, std::string* error);
/// DEPTH_U16 (times depth_scale) or DEPTH_F32 images, in metres; invalid readings become 0.
bool fromDepthImageMsg(const image_t& msg, DepthImage* depth, std::string* error);

/// CBLOX_STEREO message of a frame with a stereo pair (info.stereo must be set).
stereo_pair_t toStereoPairMsg(const CaptureFrame& frame, const SourceInfo& info, int64_t utime);
/// CBLOX_DEPTH message of a frame with depth (info.depth_intrinsics must be set).
depth_frame_t toDepthFrameMsg(const CaptureFrame& frame, const SourceInfo& info, int64_t utime,
                              DepthEncoding encoding);
/// CBLOX_GT_POSE message (frame.T_G_C must be set).
pose_stamped_t toGroundTruthMsg(const CaptureFrame& frame, int64_t utime);

/// The rectified calibration of a CBLOX_STEREO message: `rectified` must be true, both
/// calibrations distortion-free ("none") with the same intrinsics and image size (within
/// 1e-6 px), and T_L_R a pure translation (baseline_m, 0, 0) with baseline_m > 0 (rotation
/// and y, z within 1e-6). T_B_L is left_calibration.T_B_C. The images are not looked at.
std::optional<RectifiedStereoCalibration> fromStereoCalibrationMsg(const stereo_pair_t& msg,
                                                                   std::string* error);

/// CBLOX_FRAME_POSE message (tracker). `T_G_C` is absent for NOT_INITIALIZED / LOST frames:
/// the identity is sent (consumers ignore the pose of such states). `reference_keyframe_id`:
/// the keyframe the frame was tracked against, -1 (any negative value) for none.
frame_pose_t toFramePoseMsg(int64_t utime, int64_t frame_id,
                            const std::optional<Transformationd>& T_G_C, int8_t tracking_state,
                            bool tracking_jump, int32_t map_epoch,
                            int64_t reference_keyframe_id = -1);
/// CBLOX_KEYFRAME message (tracker): a new keyframe of map `map_epoch` and the landmarks it
/// observes.
keyframe_t toKeyframeMsg(int64_t utime, int64_t keyframe_id, int64_t frame_id,
                         const Transformationd& T_G_K, const std::vector<uint64_t>& landmark_ids,
                         int32_t map_epoch);
/// CBLOX_KEYFRAME_POSES message (tracker): `reason` is one of keyframe_pose_batch_t's
/// constants; T_G_K holds (keyframe id, new pose) pairs of map `map_epoch`.
keyframe_pose_batch_t toKeyframePoseBatchMsg(
    int64_t utime, int8_t reason, const std::vector<std::pair<int64_t, Transformationd>>& T_G_K,
    int32_t map_epoch);

}  // namespace cblox
