#include "core/features/stereo_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <vector>

namespace cblox {

std::string StereoMatcherConfig::validate() const {
  if (max_descriptor_distance < 0 || max_descriptor_distance > 257) {
    return "max_descriptor_distance must be in [0, 257], got " +
           std::to_string(max_descriptor_distance);
  }
  if (max_octave_difference < 0) {
    return "max_octave_difference must be >= 0, got " + std::to_string(max_octave_difference);
  }
  if (!(row_tolerance_factor > 0.0) || !std::isfinite(row_tolerance_factor)) {
    return "row_tolerance_factor must be finite and > 0, got " +
           std::to_string(row_tolerance_factor);
  }
  if (!(min_depth_m > 0.0) || !std::isfinite(min_depth_m)) {
    return "min_depth_m must be finite and > 0, got " + std::to_string(min_depth_m);
  }
  if (!(min_disparity_px >= 0.0) || !std::isfinite(min_disparity_px)) {
    return "min_disparity_px must be finite and >= 0, got " + std::to_string(min_disparity_px);
  }
  if (sad_half_window < 1 || sad_half_window > 64) {
    return "sad_half_window must be in [1, 64], got " + std::to_string(sad_half_window);
  }
  if (sad_search_half_range < 1 || sad_search_half_range > 64) {
    return "sad_search_half_range must be in [1, 64], got " + std::to_string(sad_search_half_range);
  }
  if (!(max_subpixel_shift_px > 0.0) || !std::isfinite(max_subpixel_shift_px)) {
    return "max_subpixel_shift_px must be finite and > 0, got " +
           std::to_string(max_subpixel_shift_px);
  }
  if (!(sad_outlier_factor > 0.0) || !std::isfinite(sad_outlier_factor)) {
    return "sad_outlier_factor must be finite and > 0, got " + std::to_string(sad_outlier_factor);
  }
  return "";
}

namespace {

void checkInputs(const ExtractedFeatures& left, const ExtractedFeatures& right, double fx,
                 double baseline_m, const StereoMatcherConfig& config) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("matchStereo: " + what);
  };
  const std::string error = config.validate();
  if (!error.empty()) fail("StereoMatcherConfig: " + error);
  if (!(fx > 0.0) || !std::isfinite(fx)) fail("fx must be finite and > 0");
  if (!(baseline_m > 0.0) || !std::isfinite(baseline_m)) {
    fail("baseline_m must be finite and > 0");
  }
  for (const ExtractedFeatures* f : {&left, &right}) {
    const char* side = f == &left ? "left" : "right";
    if (f->keypoints.size() != f->descriptors.size()) {
      fail(std::string(side) + " features have " + std::to_string(f->keypoints.size()) +
           " keypoints but " + std::to_string(f->descriptors.size()) + " descriptors");
    }
    if (f->pyramid.size() != static_cast<size_t>(f->scales.numLevels()) || f->pyramid.empty() ||
        f->pyramid[0].empty()) {
      fail(std::string(side) + " features have no image pyramid matching their scales");
    }
    for (const Keypoint& kp : f->keypoints) {
      if (kp.octave < 0 || kp.octave >= f->scales.numLevels()) {
        fail(std::string(side) + " keypoint with octave " + std::to_string(kp.octave) +
             " outside the pyramid");
      }
    }
  }
  if (left.scales.numLevels() != right.scales.numLevels() ||
      left.scales.scaleFactor() != right.scales.scaleFactor()) {
    fail("left and right pyramids differ in levels or scale factor");
  }
  for (size_t l = 0; l < left.pyramid.size(); ++l) {
    if (left.pyramid[l].size() != right.pyramid[l].size() || left.pyramid[l].type() != CV_8UC1 ||
        right.pyramid[l].type() != CV_8UC1) {
      fail("left and right pyramid level " + std::to_string(l) +
           " differ in size or are not CV_8UC1");
    }
  }
}

// Right keypoint indices by row (compressed rows): candidates of row r are
// index[start[r] .. start[r + 1]).
struct RowIndex {
  std::vector<int> start, index;
};

RowIndex indexRows(const ExtractedFeatures& right, int rows, double tolerance_factor) {
  RowIndex table;
  table.start.assign(static_cast<size_t>(rows) + 1, 0);
  const auto band = [&](const Keypoint& kp, int* r0, int* r1) {
    const float r = static_cast<float>(tolerance_factor) * right.scales.scale(kp.octave);
    *r0 = std::max(0, static_cast<int>(std::floor(kp.v - r)));
    *r1 = std::min(rows - 1, static_cast<int>(std::ceil(kp.v + r)));
  };
  for (const Keypoint& kp : right.keypoints) {
    int r0, r1;
    band(kp, &r0, &r1);
    for (int r = r0; r <= r1; ++r) ++table.start[static_cast<size_t>(r) + 1];
  }
  for (int r = 0; r < rows; ++r) {
    table.start[static_cast<size_t>(r) + 1] += table.start[static_cast<size_t>(r)];
  }
  table.index.resize(static_cast<size_t>(table.start.back()));
  std::vector<int> fill(table.start.begin(), table.start.end() - 1);
  for (size_t i = 0; i < right.keypoints.size(); ++i) {
    int r0, r1;
    band(right.keypoints[i], &r0, &r1);
    for (int r = r0; r <= r1; ++r) {
      table.index[static_cast<size_t>(fill[static_cast<size_t>(r)]++)] = static_cast<int>(i);
    }
  }
  return table;
}

// Sums of absolute differences between the (2w+1)^2 window centred at (ua, v) of `a` and the
// windows centred at (ub0 + k, v) of `b`, k = 0 .. count - 1, each after removing the
// brightness offset between the two windows: the difference of the window means
// (kWindowMean, each SAD times the window's pixel count so that it stays an exact integer)
// or of the centre pixels (kCentrePixel, ORB-SLAM2). sads[k] is
//   sum over the window of |scale * (a - b) + offset_k|,
// scale = (2w+1)^2 and offset_k = sum(b window k) - sum(a window) for kWindowMean, scale = 1
// and offset_k = b(v, ub0 + k) - a(v, ua) for kCentrePixel. The left window (its sum and
// scaled pixels) and the strip of `b` all the windows cover (scaled, and its column sums) are
// computed once; the right windows' sums slide along the row. The same integers as summing
// each pair of windows afresh. The windows must fit.
struct SadScratch {
  std::vector<int> scaled_a;    // the left window times scale, row by row
  std::vector<int> scaled_b;    // the strip of b the windows cover times scale, row by row
  std::vector<int> column_sum;  // b's column sums over the window's rows
};
void offsetFreeSadsAlongRow(const cv::Mat& a, int ua, const cv::Mat& b, int ub0, int count, int v,
                            int w, StereoMatcherConfig::SadReference reference, SadScratch* scratch,
                            int64_t* sads) {
  const int side = 2 * w + 1;
  const bool mean = reference == StereoMatcherConfig::SadReference::kWindowMean;
  const int scale = mean ? side * side : 1;
  std::vector<int>& scaled_a = scratch->scaled_a;
  scaled_a.resize(static_cast<size_t>(side) * static_cast<size_t>(side));
  int sum_a = 0;
  for (int y = 0; y < side; ++y) {
    const uint8_t* pa = a.ptr<uint8_t>(v - w + y) + ua - w;
    int* row = scaled_a.data() + static_cast<size_t>(y) * static_cast<size_t>(side);
    for (int x = 0; x < side; ++x) {
      sum_a += pa[x];
      row[x] = scale * pa[x];
    }
  }
  // The strip of `b` every window k covers, scaled, row by row (its multiplications done
  // once, not once per window: the SAD loop below is then subtractions, which vectorise),
  // and, for the window mean, its column sums over the window's rows.
  const int columns = count + 2 * w;
  std::vector<int>& scaled_b = scratch->scaled_b;
  std::vector<int>& column_sum = scratch->column_sum;
  scaled_b.resize(static_cast<size_t>(side) * static_cast<size_t>(columns));
  column_sum.assign(mean ? static_cast<size_t>(columns) : 0, 0);
  for (int y = 0; y < side; ++y) {
    const uint8_t* pb = b.ptr<uint8_t>(v - w + y) + ub0 - w;
    int* row = scaled_b.data() + static_cast<size_t>(y) * static_cast<size_t>(columns);
    for (int c = 0; c < columns; ++c) row[c] = scale * pb[c];
    if (mean) {
      for (int c = 0; c < columns; ++c) column_sum[static_cast<size_t>(c)] += pb[c];
    }
  }
  int window_sum = 0;
  if (mean) {
    for (int c = 0; c < side; ++c) window_sum += column_sum[static_cast<size_t>(c)];
  }
  const int centre_a = a.at<uint8_t>(v, ua);
  for (int k = 0; k < count; ++k) {
    if (mean && k > 0) {
      window_sum +=
          column_sum[static_cast<size_t>(k + side - 1)] - column_sum[static_cast<size_t>(k - 1)];
    }
    const int offset =
        mean ? window_sum - sum_a : static_cast<int>(b.at<uint8_t>(v, ub0 + k)) - centre_a;
    int64_t sad = 0;
    for (int y = 0; y < side; ++y) {
      const int* ra = scaled_a.data() + static_cast<size_t>(y) * static_cast<size_t>(side);
      const int* rb = scaled_b.data() + static_cast<size_t>(y) * static_cast<size_t>(columns) +
                      static_cast<size_t>(k);
      int row_sad = 0;
      for (int x = 0; x < side; ++x) row_sad += std::abs(ra[x] - rb[x] + offset);
      sad += row_sad;
    }
    sads[k] = sad;
  }
}

}  // namespace

StereoDepth matchStereo(const ExtractedFeatures& left, const ExtractedFeatures& right, double fx,
                        double baseline_m, const StereoMatcherConfig& config) {
  checkInputs(left, right, fx, baseline_m, config);
  const size_t n = left.keypoints.size();
  StereoDepth out;
  out.right_u.assign(n, -1.0f);
  out.depth.assign(n, -1.0f);
  out.right_index.assign(n, -1);
  if (n == 0 || right.keypoints.empty()) return out;

  const int rows = left.pyramid[0].rows;
  const RowIndex table = indexRows(right, rows, config.row_tolerance_factor);
  const double bf = fx * baseline_m;
  const double max_disparity = bf / config.min_depth_m;
  const auto row_tolerance = static_cast<float>(config.row_tolerance_factor);
  const int w = config.sad_half_window;
  const int range = config.sad_search_half_range;
  std::vector<int64_t> sads(static_cast<size_t>(2 * range + 1));
  SadScratch scratch;
  std::vector<std::pair<int64_t, int>> sad_of_match;  // (best SAD, left index)
  sad_of_match.reserve(n);

  for (size_t il = 0; il < n; ++il) {
    const Keypoint& kl = left.keypoints[il];
    const int row = static_cast<int>(std::lround(kl.v));
    if (row < 0 || row >= rows) continue;
    const double min_u = kl.u - max_disparity;
    const double max_u = kl.u - config.min_disparity_px;
    if (max_u < 0.0) continue;

    // Best descriptor match among the candidates.
    int best_distance = std::numeric_limits<int>::max();
    int best_r = -1;
    for (int k = table.start[static_cast<size_t>(row)];
         k < table.start[static_cast<size_t>(row) + 1]; ++k) {
      const int ir = table.index[static_cast<size_t>(k)];
      const Keypoint& kr = right.keypoints[static_cast<size_t>(ir)];
      if (std::abs(kr.octave - kl.octave) > config.max_octave_difference) continue;
      if (kr.u < min_u || kr.u > max_u) continue;
      // The row table holds whole rows; the tolerance itself is exact.
      if (std::abs(kr.v - kl.v) > row_tolerance * right.scales.scale(kr.octave)) continue;
      const int d =
          hammingDistance(left.descriptors[il], right.descriptors[static_cast<size_t>(ir)]);
      if (d < best_distance) {
        best_distance = d;
        best_r = ir;
      }
    }
    if (best_r < 0 || best_distance >= config.max_descriptor_distance) continue;

    // SAD refinement at the left keypoint's level.
    const int level = kl.octave;
    const cv::Mat& il_img = left.pyramid[static_cast<size_t>(level)];
    const cv::Mat& ir_img = right.pyramid[static_cast<size_t>(level)];
    const float inv_scale = left.scales.invScale(level);
    const int ul = static_cast<int>(std::lround(kl.u * inv_scale));
    const int vl = static_cast<int>(std::lround(kl.v * inv_scale));
    const int ur0 =
        static_cast<int>(std::lround(right.keypoints[static_cast<size_t>(best_r)].u * inv_scale));
    if (vl - w < 0 || vl + w >= il_img.rows || ul - w < 0 || ul + w >= il_img.cols ||
        ur0 - range - w < 0 || ur0 + range + w >= ir_img.cols) {
      continue;
    }
    offsetFreeSadsAlongRow(il_img, ul, ir_img, ur0 - range, 2 * range + 1, vl, w,
                           config.sad_reference, &scratch, sads.data());
    int64_t best_sad = std::numeric_limits<int64_t>::max();
    int best_inc = 0;
    for (int inc = -range; inc <= range; ++inc) {
      const int64_t sad = sads[static_cast<size_t>(inc + range)];
      if (sad < best_sad) {
        best_sad = sad;
        best_inc = inc;
      }
    }
    if (best_inc == -range || best_inc == range) continue;
    const float d1 = static_cast<float>(sads[static_cast<size_t>(best_inc + range - 1)]);
    const float d2 = static_cast<float>(sads[static_cast<size_t>(best_inc + range)]);
    const float d3 = static_cast<float>(sads[static_cast<size_t>(best_inc + range + 1)]);
    // Sub-pixel minimum: parabola (ORB-SLAM2) or equiangular lines (a "V" with equal slopes,
    // the shape of an L1 cost) through the best offset and its neighbours.
    const float curvature = config.subpixel_fit == StereoMatcherConfig::SubpixelFit::kParabola
                                ? 2.0f * (d1 + d3 - 2.0f * d2)
                                : 2.0f * (std::max(d1, d3) - d2);
    if (!(curvature > 0.0f)) continue;  // flat: no sub-pixel minimum
    const float shift = (d1 - d3) / curvature;
    if (std::abs(shift) > static_cast<float>(config.max_subpixel_shift_px)) continue;

    const float right_u = left.scales.scale(level) * (static_cast<float>(ur0 + best_inc) + shift);
    const double disparity = static_cast<double>(kl.u) - static_cast<double>(right_u);
    if (!(disparity > config.min_disparity_px) || !(disparity < max_disparity)) continue;
    out.right_u[il] = right_u;
    out.depth[il] = static_cast<float>(bf / disparity);
    out.right_index[il] = best_r;
    sad_of_match.emplace_back(best_sad, static_cast<int>(il));
  }

  // Outlier rejection by SAD: more than sad_outlier_factor times the median.
  if (!sad_of_match.empty()) {
    std::vector<int64_t> values(sad_of_match.size());
    for (size_t i = 0; i < values.size(); ++i) values[i] = sad_of_match[i].first;
    std::nth_element(values.begin(),
                     values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
    const double threshold =
        config.sad_outlier_factor * static_cast<double>(values[values.size() / 2]);
    for (const auto& [sad, il] : sad_of_match) {
      if (static_cast<double>(sad) > threshold) {
        out.right_u[static_cast<size_t>(il)] = -1.0f;
        out.depth[static_cast<size_t>(il)] = -1.0f;
        out.right_index[static_cast<size_t>(il)] = -1;
      }
    }
  }
  return out;
}

}  // namespace cblox
