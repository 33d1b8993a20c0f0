#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace cblox {

/// The smoothing ORB applies to a pyramid level before rotated BRIEF's intensity tests: a 7x7
/// Gaussian, sigma 2, BORDER_REFLECT_101, computed the way OpenCV's ORB computes it. OpenCV's
/// ORB blurs each level in place as a window of a buffer whose border holds the level's
/// reflection; for a window cv::GaussianBlur takes its generic separable path, which for 8-bit
/// images filters in floats with the normalised kernel g (0.0702, 0.1311, 0.1907, 0.2161, ...):
///   row pass r = g_0 I(x - 3) + ... + g_6 I(x + 3), accumulated left to right with fused
///   multiply-adds (OpenCV's AVX2 build);
///   column pass s = g_3 r(y) + g_4 (r(y + 1) + r(y - 1)) + g_5 (...) + g_6 (...), likewise;
///   result = s rounded half to even, saturated to [0, 255].
/// (OpenCV's bit-exact path for whole images rounds differently; ORB-SLAM2 uses that one, so
/// its descriptors differ slightly from OpenCV's ORB. cblox follows OpenCV's ORB.)
///
/// apply() computes this with AVX2 and FMA on CPUs that have them (8 and 16 pixels at a time,
/// the same operations in the same order, so the same bytes as OpenCV on such a CPU), else
/// with cv::GaussianBlur as OpenCV's ORB calls it (applyOpenCv()).
/// Not thread-safe (reuses buffers): one per thread.
class BriefBlur {
 public:
  /// *dst becomes the blurred `level` (CV_8UC1, any step; must not share memory with *dst).
  /// Throws std::invalid_argument for another type or an empty level.
  void apply(const cv::Mat& level, cv::Mat* dst);

  /// The reference: cv::GaussianBlur in place on a window of a buffer padded with the level's
  /// BORDER_REFLECT_101 extension, exactly as OpenCV's ORB. *dst becomes a view into that
  /// buffer (valid until the next call).
  void applyOpenCv(const cv::Mat& level, cv::Mat* dst);

 private:
  cv::Mat padded_;           // applyOpenCv's buffer
  std::vector<float> row_;   // one source row in floats with its 3-pixel reflections
  std::vector<float> ring_;  // the row pass of the last 8 rows
};

}  // namespace cblox
