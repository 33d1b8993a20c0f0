#include "core/eval/colormap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace cblox {
namespace {

using Table = std::array<Color, 256>;

Table buildViridis() {
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<uint8_t>(0, i) = static_cast<uint8_t>(i);
  cv::Mat bgr;
  cv::applyColorMap(ramp, bgr, cv::COLORMAP_VIRIDIS);
  Table table;
  for (int i = 0; i < 256; ++i) {
    const cv::Vec3b& c = bgr.at<cv::Vec3b>(0, i);
    table[static_cast<size_t>(i)] = Color{c[2], c[1], c[0]};
  }
  return table;
}

uint8_t mix(uint8_t a, uint8_t b, double f) {
  return static_cast<uint8_t>(std::lround(a + f * (static_cast<double>(b) - a)));
}

}  // namespace

Color colormap(double t) {
  static const Table table = buildViridis();
  if (std::isnan(t)) t = 0.0;
  const double x = std::clamp(t, 0.0, 1.0) * 255.0;
  const size_t i = std::min<size_t>(static_cast<size_t>(x), 254);
  const double f = x - static_cast<double>(i);
  const Color& a = table[i];
  const Color& b = table[i + 1];
  return Color{mix(a.r, b.r, f), mix(a.g, b.g, f), mix(a.b, b.b, f)};
}

std::vector<double> niceTicks(double min_value, double max_value, int target_count) {
  if (!std::isfinite(min_value) || !std::isfinite(max_value) || !(max_value > min_value)) {
    return {};
  }
  const double range = max_value - min_value;
  const double raw = range / std::clamp(target_count, 1, 1000);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double normalised = raw / magnitude;
  const double factor = normalised < 1.5   ? 1.0
                        : normalised < 3.0 ? 2.0
                        : normalised < 7.0 ? 5.0
                                           : 10.0;
  const double step = factor * magnitude;
  std::vector<double> ticks;
  const double first = std::ceil(min_value / step - 1e-9);
  const double last = std::floor(max_value / step + 1e-9);
  for (double k = first; k <= last && ticks.size() < 2000; k += 1.0) ticks.push_back(k * step);
  return ticks;
}

std::string formatTick(double value, double step) {
  int decimals = 0;
  if (std::isfinite(step) && step > 0.0) {
    // Fewest decimals that write the step itself exactly (to 1e-6 relative).
    for (double scaled = step; decimals < 9; ++decimals, scaled *= 10.0) {
      if (std::abs(scaled - std::round(scaled)) <= 1e-6 * scaled) break;
    }
  }
  if (std::isfinite(step) && std::abs(value) < 1e-9 * std::abs(step)) value = 0.0;
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  std::string text(buffer);
  if (text.find_first_not_of("-0.") == std::string::npos && text[0] == '-') text.erase(0, 1);
  return text;
}

void drawColorBar(ColorImage* image, int x, int y, int width, int height, double min_value,
                  double max_value, const std::string& unit) {
  if (image == nullptr || image->empty() || width < 1 || height < 1) return;
  if (image->data.size() !=
      static_cast<size_t>(image->width) * static_cast<size_t>(image->height)) {
    return;
  }
  static_assert(sizeof(Color) == 3, "Color must be 3 packed bytes to wrap it as CV_8UC3");
  // View of the image memory; its channel order is R, G, B, so scalars are (r, g, b).
  cv::Mat view(image->height, image->width, CV_8UC3, image->data.data());
  for (int row = 0; row < height; ++row) {
    const int v = y + row;
    if (v < 0 || v >= image->height) continue;
    const double f = height == 1 ? 1.0 : 1.0 - static_cast<double>(row) / (height - 1);
    const Color c = colormap(f);
    for (int u = std::max(x, 0); u < std::min(x + width, image->width); ++u) (*image)(u, v) = c;
  }
  const cv::Scalar black(0, 0, 0);
  cv::rectangle(view, cv::Point(x - 1, y - 1), cv::Point(x + width, y + height), black, 1);

  constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
  constexpr double kScale = 0.4;
  const auto label = [&](double value, const std::string& text) {
    const double f = max_value > min_value ? (value - min_value) / (max_value - min_value) : 0.0;
    const int v = y + static_cast<int>(std::lround((1.0 - f) * (height - 1)));
    cv::line(view, cv::Point(x + width, v), cv::Point(x + width + 4, v), black, 1);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, kFont, kScale, 1, &baseline);
    cv::putText(view, text, cv::Point(x + width + 7, v + size.height / 2), kFont, kScale, black, 1,
                cv::LINE_AA);
  };
  const std::vector<double> ticks = niceTicks(min_value, max_value, 5);
  if (ticks.empty()) {
    if (std::isfinite(min_value)) label(min_value, formatTick(min_value, 0.001));
  } else {
    const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : max_value - min_value;
    for (const double tick : ticks) label(tick, formatTick(tick, step));
  }
  if (!unit.empty()) {
    cv::putText(view, unit, cv::Point(x, y - 8), kFont, kScale, black, 1, cv::LINE_AA);
  }
}

}  // namespace cblox
