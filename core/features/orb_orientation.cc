#include "core/features/orb_orientation.h"

#include <cmath>

namespace cblox {

OrbOrientation::OrbOrientation() {
  // Row extents of the discrete circle of radius 15, made symmetric about the diagonal (the
  // construction of OpenCV's ORB and ORB-SLAM2, so the moments, hence angles, equal theirs).
  constexpr int kR = kOrbHalfPatchSize;
  const int vmax = cvFloor(kR * std::sqrt(2.f) / 2 + 1);
  const int vmin = cvCeil(kR * std::sqrt(2.f) / 2);
  const double r2 = static_cast<double>(kR) * kR;
  for (int v = 0; v <= vmax; ++v) {
    umax_[static_cast<size_t>(v)] = cvRound(std::sqrt(r2 - v * v));
  }
  for (int v = kR, v0 = 0; v >= vmin; --v) {
    while (umax_[static_cast<size_t>(v0)] == umax_[static_cast<size_t>(v0 + 1)]) ++v0;
    umax_[static_cast<size_t>(v)] = v0;
    ++v0;
  }
}

float OrbOrientation::angleDeg(const cv::Mat& level, int x, int y) const {
  const uint8_t* center = level.ptr<uint8_t>(y) + x;
  const int step = static_cast<int>(level.step1());
  int m01 = 0, m10 = 0;
  for (int u = -kOrbHalfPatchSize; u <= kOrbHalfPatchSize; ++u) m10 += u * center[u];
  for (int v = 1; v <= kOrbHalfPatchSize; ++v) {
    const uint8_t* plus = center + v * step;
    const uint8_t* minus = center - v * step;
    const int d = umax_[static_cast<size_t>(v)];
    int v_sum = 0;
    for (int u = -d; u <= d; ++u) {
      const int p = plus[u], m = minus[u];
      v_sum += p - m;
      m10 += u * (p + m);
    }
    m01 += v * v_sum;
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

}  // namespace cblox
