#include "daemon/common/lcm_messages.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace cblox {
namespace {

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

int bytesPerPixel(int8_t format) {
  switch (format) {
    case image_t::GRAY8:
      return 1;
    case image_t::RGB8:
    case image_t::BGR8:
      return 3;
    case image_t::RGBA8:
    case image_t::DEPTH_F32:
      return 4;
    case image_t::DEPTH_U16:
      return 2;
    default:
      return 0;
  }
}

/// Checks size fields; returns the bytes per pixel, or 0 with a message.
int checkImage(const image_t& msg, std::string* error) {
  const int bpp = bytesPerPixel(msg.pixel_format);
  if (bpp == 0) {
    setError(error, "image " + msg.camera_id + ": unknown pixel_format " +
                        std::to_string(static_cast<int>(msg.pixel_format)));
    return 0;
  }
  if (msg.width <= 0 || msg.height <= 0 || msg.width > 16384 || msg.height > 16384) {
    setError(error, "image " + msg.camera_id + ": bad size " + std::to_string(msg.width) + "x" +
                        std::to_string(msg.height));
    return 0;
  }
  if (msg.row_stride < msg.width * bpp) {
    setError(error, "image " + msg.camera_id + ": row_stride " + std::to_string(msg.row_stride) +
                        " < width * " + std::to_string(bpp));
    return 0;
  }
  const int64_t needed = static_cast<int64_t>(msg.row_stride) * msg.height;
  if (msg.size != needed || static_cast<int64_t>(msg.data.size()) != needed) {
    setError(error, "image " + msg.camera_id + ": data has " + std::to_string(msg.data.size()) +
                        " bytes (size field " + std::to_string(msg.size) + "), expected " +
                        std::to_string(needed));
    return 0;
  }
  return bpp;
}

image_t emptyImage(int64_t utime, const std::string& camera_id, int width, int height,
                   int8_t format, double depth_scale) {
  image_t msg;
  msg.utime = utime;
  msg.camera_id = camera_id;
  msg.width = width;
  msg.height = height;
  msg.pixel_format = format;
  msg.row_stride = width * bytesPerPixel(format);
  msg.depth_scale = depth_scale;
  msg.size = msg.row_stride * height;
  msg.data.resize(static_cast<size_t>(msg.size));
  return msg;
}

}  // namespace

pose_t toPoseMsg(const Transformationd& T) {
  pose_t msg;
  for (int i = 0; i < 3; ++i) msg.position[i] = T.translation()[i];
  const Eigen::Quaterniond& q = T.rotation();
  msg.orientation[0] = q.w();
  msg.orientation[1] = q.x();
  msg.orientation[2] = q.y();
  msg.orientation[3] = q.z();
  return msg;
}

std::optional<Transformationd> fromPoseMsg(const pose_t& msg, std::string* error) {
  const Eigen::Vector3d t(msg.position[0], msg.position[1], msg.position[2]);
  const Eigen::Quaterniond q(msg.orientation[0], msg.orientation[1], msg.orientation[2],
                             msg.orientation[3]);
  if (!t.allFinite() || !q.coeffs().allFinite()) {
    setError(error, "pose has non-finite values");
    return std::nullopt;
  }
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    setError(error, "pose quaternion norm is " + std::to_string(q.norm()) + ", not 1");
    return std::nullopt;
  }
  return Transformationd(q.normalized(), t);
}

camera_calibration_t toCalibrationMsg(const std::string& camera_id,
                                      const PinholeIntrinsics& intrinsics,
                                      const Transformationd& T_B_C) {
  camera_calibration_t msg;
  msg.camera_id = camera_id;
  msg.width = intrinsics.width;
  msg.height = intrinsics.height;
  msg.fx = intrinsics.fx;
  msg.fy = intrinsics.fy;
  msg.cx = intrinsics.cx;
  msg.cy = intrinsics.cy;
  msg.distortion_model = "none";
  msg.num_distortion = 0;
  msg.T_B_C = toPoseMsg(T_B_C);
  return msg;
}

std::optional<PinholeIntrinsics> fromCalibrationMsg(const camera_calibration_t& msg,
                                                    std::string* error) {
  if (msg.distortion_model != "none") {
    setError(error, "calibration " + msg.camera_id + ": distortion_model '" + msg.distortion_model +
                        "' (only 'none' is accepted here)");
    return std::nullopt;
  }
  const PinholeIntrinsics intrinsics{msg.fx, msg.fy, msg.cx, msg.cy, msg.width, msg.height};
  if (const std::string problem = validate(intrinsics); !problem.empty()) {
    setError(error, "calibration " + msg.camera_id + ": " + problem);
    return std::nullopt;
  }
  return intrinsics;
}

image_t toImageMsg(const GrayImage& image, int64_t utime, const std::string& camera_id) {
  image_t msg = emptyImage(utime, camera_id, image.width, image.height, image_t::GRAY8, 0.0);
  std::memcpy(msg.data.data(), image.data.data(), image.data.size());
  return msg;
}

image_t toImageMsg(const ColorImage& image, int64_t utime, const std::string& camera_id) {
  image_t msg = emptyImage(utime, camera_id, image.width, image.height, image_t::RGB8, 0.0);
  static_assert(sizeof(Color) == 3);
  std::memcpy(msg.data.data(), image.data.data(), image.data.size() * 3);
  return msg;
}

image_t toDepthImageMsg(const DepthImage& depth, int64_t utime, const std::string& camera_id,
                        DepthEncoding encoding) {
  if (encoding == DepthEncoding::kFloat32Metres) {
    image_t msg = emptyImage(utime, camera_id, depth.width, depth.height, image_t::DEPTH_F32, 1.0);
    for (size_t i = 0; i < depth.data.size(); ++i) {
      const float d = std::isfinite(depth.data[i]) && depth.data[i] > 0.0f ? depth.data[i] : 0.0f;
      std::memcpy(msg.data.data() + 4 * i, &d, 4);  // little-endian host
    }
    return msg;
  }
  image_t msg = emptyImage(utime, camera_id, depth.width, depth.height, image_t::DEPTH_U16, 0.001);
  for (size_t i = 0; i < depth.data.size(); ++i) {
    const float d = depth.data[i];
    uint16_t mm = 0;
    if (std::isfinite(d) && d > 0.0f) {
      mm = static_cast<uint16_t>(std::min(65535.0f, std::round(d * 1000.0f)));
    }
    msg.data[2 * i] = static_cast<uint8_t>(mm & 0xFF);
    msg.data[2 * i + 1] = static_cast<uint8_t>(mm >> 8);
  }
  return msg;
}

bool fromImageMsg(const image_t& msg, GrayImage* image, std::string* error) {
  const int bpp = checkImage(msg, error);
  if (bpp == 0) return false;
  if (msg.pixel_format == image_t::DEPTH_U16 || msg.pixel_format == image_t::DEPTH_F32) {
    setError(error, "image " + msg.camera_id + ": a depth image is not an intensity image");
    return false;
  }
  *image = GrayImage(msg.width, msg.height);
  for (int v = 0; v < msg.height; ++v) {
    const uint8_t* row = msg.data.data() + static_cast<size_t>(v) * msg.row_stride;
    for (int u = 0; u < msg.width; ++u) {
      const uint8_t* p = row + static_cast<size_t>(u) * bpp;
      if (bpp == 1) {
        (*image)(u, v) = p[0];
      } else {
        const bool bgr = msg.pixel_format == image_t::BGR8;
        const int r = bgr ? p[2] : p[0], g = p[1], b = bgr ? p[0] : p[2];
        (*image)(u, v) = static_cast<uint8_t>((299 * r + 587 * g + 114 * b + 500) / 1000);
      }
    }
  }
  return true;
}

bool fromImageMsg(const image_t& msg, ColorImage* image, std::string* error) {
  const int bpp = checkImage(msg, error);
  if (bpp == 0) return false;
  if (msg.pixel_format == image_t::DEPTH_U16 || msg.pixel_format == image_t::DEPTH_F32) {
    setError(error, "image " + msg.camera_id + ": a depth image is not a colour image");
    return false;
  }
  *image = ColorImage(msg.width, msg.height);
  const bool bgr = msg.pixel_format == image_t::BGR8;
  for (int v = 0; v < msg.height; ++v) {
    const uint8_t* row = msg.data.data() + static_cast<size_t>(v) * msg.row_stride;
    for (int u = 0; u < msg.width; ++u) {
      const uint8_t* p = row + static_cast<size_t>(u) * bpp;
      (*image)(u, v) =
          bpp == 1 ? Color{p[0], p[0], p[0]} : Color{bgr ? p[2] : p[0], p[1], bgr ? p[0] : p[2]};
    }
  }
  return true;
}

bool fromDepthImageMsg(const image_t& msg, DepthImage* depth, std::string* error) {
  const int bpp = checkImage(msg, error);
  if (bpp == 0) return false;
  if (msg.pixel_format != image_t::DEPTH_U16 && msg.pixel_format != image_t::DEPTH_F32) {
    setError(error, "depth image " + msg.camera_id + ": pixel_format " +
                        std::to_string(static_cast<int>(msg.pixel_format)) +
                        " is not DEPTH_U16 or DEPTH_F32");
    return false;
  }
  if (msg.pixel_format == image_t::DEPTH_U16 &&
      (!(msg.depth_scale > 0.0) || !std::isfinite(msg.depth_scale))) {
    setError(error, "depth image " + msg.camera_id + ": depth_scale must be > 0 for DEPTH_U16");
    return false;
  }
  *depth = DepthImage(msg.width, msg.height);
  for (int v = 0; v < msg.height; ++v) {
    const uint8_t* row = msg.data.data() + static_cast<size_t>(v) * msg.row_stride;
    for (int u = 0; u < msg.width; ++u) {
      float d;
      if (msg.pixel_format == image_t::DEPTH_U16) {
        const uint16_t raw = static_cast<uint16_t>(row[2 * u] | (row[2 * u + 1] << 8));
        d = static_cast<float>(raw * msg.depth_scale);
      } else {
        std::memcpy(&d, row + 4 * u, 4);
        if (!std::isfinite(d) || d < 0.0f) d = 0.0f;
      }
      (*depth)(u, v) = d;
    }
  }
  return true;
}

stereo_pair_t toStereoPairMsg(const CaptureFrame& frame, const SourceInfo& info, int64_t utime) {
  stereo_pair_t msg;
  msg.utime = utime;
  msg.frame_id = frame.frame_id;
  msg.left = toImageMsg(frame.left, utime, "left");
  msg.right = toImageMsg(frame.right, utime, "right");
  const RectifiedStereoCalibration& stereo = *info.stereo;
  msg.left_calibration = toCalibrationMsg("left", stereo.intrinsics, stereo.T_B_L);
  const Transformationd T_L_R(Eigen::Quaterniond::Identity(),
                              Eigen::Vector3d(stereo.baseline_m, 0.0, 0.0));
  msg.right_calibration = toCalibrationMsg("right", stereo.intrinsics, stereo.T_B_L * T_L_R);
  msg.T_L_R = toPoseMsg(T_L_R);
  msg.rectified = true;
  return msg;
}

depth_frame_t toDepthFrameMsg(const CaptureFrame& frame, const SourceInfo& info, int64_t utime,
                              DepthEncoding encoding) {
  depth_frame_t msg;
  msg.utime = utime;
  msg.frame_id = frame.frame_id;
  msg.depth = toDepthImageMsg(frame.depth, utime, "depth", encoding);
  msg.has_color = !frame.color.empty();
  msg.color = msg.has_color ? toImageMsg(frame.color, utime, "depth")
                            : emptyImage(utime, "depth", 0, 0, image_t::RGB8, 0.0);
  msg.calibration = toCalibrationMsg("depth", *info.depth_intrinsics,
                                     info.stereo ? info.stereo->T_B_L * info.T_C_D : info.T_C_D);
  msg.min_depth_m = static_cast<float>(info.depth_min_m);
  msg.max_depth_m = static_cast<float>(info.depth_max_m);
  return msg;
}

pose_stamped_t toGroundTruthMsg(const CaptureFrame& frame, int64_t utime) {
  pose_stamped_t msg;
  msg.utime = utime;
  msg.frame_id = frame.frame_id;
  msg.frame.assign(1, 'G');  // not = "G": GCC 12 -Wrestrict false positive at -O3
  msg.T_G_C = toPoseMsg(*frame.T_G_C);
  return msg;
}

std::optional<RectifiedStereoCalibration> fromStereoCalibrationMsg(const stereo_pair_t& msg,
                                                                   std::string* error) {
  if (!msg.rectified) {
    setError(error, "stereo pair: not rectified (rectified = false)");
    return std::nullopt;
  }
  const std::optional<PinholeIntrinsics> left = fromCalibrationMsg(msg.left_calibration, error);
  if (!left) return std::nullopt;
  const std::optional<PinholeIntrinsics> right = fromCalibrationMsg(msg.right_calibration, error);
  if (!right) return std::nullopt;
  constexpr double kPixelTolerance = 1e-6;
  if (left->width != right->width || left->height != right->height ||
      std::abs(left->fx - right->fx) > kPixelTolerance ||
      std::abs(left->fy - right->fy) > kPixelTolerance ||
      std::abs(left->cx - right->cx) > kPixelTolerance ||
      std::abs(left->cy - right->cy) > kPixelTolerance) {
    setError(error,
             "stereo pair: left and right calibrations differ (a rectified pair shares "
             "its intrinsics and image size)");
    return std::nullopt;
  }
  const std::optional<Transformationd> T_B_L = fromPoseMsg(msg.left_calibration.T_B_C, error);
  if (!T_B_L) {
    if (error != nullptr) *error = "stereo pair: left_calibration.T_B_C: " + *error;
    return std::nullopt;
  }
  const std::optional<Transformationd> T_L_R = fromPoseMsg(msg.T_L_R, error);
  if (!T_L_R) {
    if (error != nullptr) *error = "stereo pair: T_L_R: " + *error;
    return std::nullopt;
  }
  constexpr double kGeometryTolerance = 1e-6;
  const Eigen::Vector3d& t = T_L_R->translation();
  if (T_L_R->rotation().angularDistance(Eigen::Quaterniond::Identity()) > kGeometryTolerance ||
      std::abs(t.y()) > kGeometryTolerance || std::abs(t.z()) > kGeometryTolerance ||
      !(t.x() > 0.0)) {
    setError(error,
             "stereo pair: T_L_R must be a translation (baseline > 0, 0, 0) without "
             "rotation for a rectified pair, got position (" +
                 std::to_string(t.x()) + ", " + std::to_string(t.y()) + ", " +
                 std::to_string(t.z()) + ")");
    return std::nullopt;
  }
  RectifiedStereoCalibration calibration;
  calibration.intrinsics = *left;
  calibration.baseline_m = t.x();
  calibration.T_B_L = *T_B_L;
  return calibration;
}

frame_pose_t toFramePoseMsg(int64_t utime, int64_t frame_id,
                            const std::optional<Transformationd>& T_G_C, int8_t tracking_state,
                            bool tracking_jump, int32_t map_epoch,
                            int64_t reference_keyframe_id) {
  frame_pose_t msg{};
  msg.utime = utime;
  msg.frame_id = frame_id;
  msg.T_G_C = toPoseMsg(T_G_C.value_or(Transformationd::Identity()));
  msg.tracking_state = tracking_state;
  msg.tracking_jump = tracking_jump;
  msg.map_epoch = map_epoch;
  msg.reference_keyframe_id = reference_keyframe_id < 0 ? -1 : reference_keyframe_id;
  return msg;
}

keyframe_t toKeyframeMsg(int64_t utime, int64_t keyframe_id, int64_t frame_id,
                         const Transformationd& T_G_K, const std::vector<uint64_t>& landmark_ids,
                         int32_t map_epoch) {
  keyframe_t msg;
  msg.utime = utime;
  msg.map_epoch = map_epoch;
  msg.keyframe_id = keyframe_id;
  msg.frame_id = frame_id;
  msg.T_G_K = toPoseMsg(T_G_K);
  msg.landmark_ids.assign(landmark_ids.begin(), landmark_ids.end());
  msg.num_landmarks = static_cast<int32_t>(msg.landmark_ids.size());
  return msg;
}

keyframe_pose_batch_t toKeyframePoseBatchMsg(
    int64_t utime, int8_t reason, const std::vector<std::pair<int64_t, Transformationd>>& T_G_K,
    int32_t map_epoch) {
  keyframe_pose_batch_t msg;
  msg.utime = utime;
  msg.map_epoch = map_epoch;
  msg.reason = reason;
  msg.keyframe_ids.reserve(T_G_K.size());
  msg.poses.reserve(T_G_K.size());
  for (const auto& [id, T] : T_G_K) {
    msg.keyframe_ids.push_back(id);
    msg.poses.push_back(toPoseMsg(T));
  }
  msg.num_keyframes = static_cast<int32_t>(msg.keyframe_ids.size());
  return msg;
}

}  // namespace cblox
