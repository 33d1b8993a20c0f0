#pragma once

// Frames held in memory for benchmarks, so file decoding is never timed.

#include <string>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"

namespace cblox::bench {

struct BenchFrame {
  Transformationd T_G_C;
  DepthImage depth;  // metres, 0 = invalid
  ColorImage color;
};

struct BenchSequence {
  PinholeIntrinsics intrinsics;
  std::vector<BenchFrame> frames;
};

}  // namespace cblox::bench
