#pragma once

// Turns one V4L2 frame into the images a CaptureFrame carries, by source mode.

#include "core/geometry/image.h"
#include "drivers/pixel/raw_image.h"
#include "drivers/v4l2/v4l2_source_config.h"

namespace cblox {

/// Images decoded from one device frame. Plain value type.
struct V4l2Images {
  GrayImage left, right;
  DepthImage depth;
  ColorImage color;
};

/// Decodes `raw` for `mode` into *out (non-null; all its images are reset first):
///   kMono        left = toGray(raw); color = toColor(raw) if `color` and raw is not grey
///   kDepth       depth = toDepth(raw, depth_scale_m)
///   kStereoPair  left = toGray(raw) (one camera of the pair; the caller assigns the side)
///   kSideBySide  left, right = splitSideBySide(toGray(raw)): halves of width raw.width / 2;
///                for kY8i splitInterleaved(raw): each view the full raw.width
/// Returns the first failing conversion's result. Thread-safe (no shared state).
ConvertResult decodeV4l2Frame(V4l2Mode mode, const RawImage& raw, bool color, double depth_scale_m,
                              V4l2Images* out);

}  // namespace cblox
