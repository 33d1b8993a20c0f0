#include "drivers/v4l2/v4l2_frame_decoder.h"

#include "drivers/pixel/pixel_convert.h"

namespace cblox {

ConvertResult decodeV4l2Frame(V4l2Mode mode, const RawImage& raw, bool color, double depth_scale_m,
                              V4l2Images* out) {
  *out = V4l2Images{};
  switch (mode) {
    case V4l2Mode::kDepth:
      return toDepth(raw, depth_scale_m, &out->depth);
    case V4l2Mode::kSideBySide: {
      if (raw.format == PixelFormat::kY8i) {
        return splitInterleaved(raw, &out->left, &out->right);  // full-width views
      }
      GrayImage both;
      if (ConvertResult result = toGray(raw, &both); !result) return result;
      return splitSideBySide(both, &out->left, &out->right);
    }
    case V4l2Mode::kMono: {
      if (ConvertResult result = toGray(raw, &out->left); !result) return result;
      const bool grey = raw.format == PixelFormat::kGrey || raw.format == PixelFormat::kY16;
      if (color && !grey) return toColor(raw, &out->color);
      return {};
    }
    case V4l2Mode::kStereoPair:
      return toGray(raw, &out->left);
  }
  return ConvertResult{ConvertError::kUnsupported, "unknown V4L2 source mode"};
}

}  // namespace cblox
