#include "core/eval/scatter_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/eval/colormap.h"
#include "core/eval/trajectory_plot.h"

namespace cblox {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kLabelScale = 0.45;
constexpr double kTitleScale = 0.6;
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(225, 225, 225);
const cv::Scalar kText(40, 40, 40);

// RGB (the view is RGB): series 0 steel blue-grey, 1 red, then tab10.
const std::array<cv::Scalar, 6> kSeriesColors = {
    cv::Scalar(90, 110, 140), cv::Scalar(214, 39, 40),   cv::Scalar(44, 160, 44),
    cv::Scalar(255, 127, 14), cv::Scalar(148, 103, 189), cv::Scalar(140, 86, 75)};

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

struct Axis {
  double min = 0.0, max = 1.0;
  int pixel_begin = 0, pixel_end = 1;  // pixel of min, pixel of max
  double operator()(double value) const {
    return pixel_begin + (value - min) / (max - min) * (pixel_end - pixel_begin);
  }
};

Axis makeAxis(double lo, double hi, int pixel_begin, int pixel_end) {
  if (lo > 0.0) lo = 0.0;  // positive data: start at zero
  double span = hi - lo;
  if (!(span > 0.0)) span = 1.0;
  Axis axis;
  axis.min = lo - (lo < 0.0 ? 0.08 * span : 0.0);
  axis.max = hi + 0.08 * span;
  axis.pixel_begin = pixel_begin;
  axis.pixel_end = pixel_end;
  return axis;
}

void text(cv::Mat& view, const std::string& s, cv::Point origin, double scale,
          const cv::Scalar& colour = kText) {
  cv::putText(view, s, origin, kFont, scale, colour, 1, cv::LINE_AA);
}

cv::Size textSize(const std::string& s, double scale) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, 1, &baseline);
}

}  // namespace

std::string ScatterPlotConfig::validate() const {
  if (width < 200 || width > 10000) return "width must be in [200, 10000]";
  if (height < 150 || height > 10000) return "height must be in [150, 10000]";
  return {};
}

std::optional<ColorImage> renderScatterPlot(const std::vector<ScatterPoint>& points,
                                            const ScatterPlotConfig& options, std::string* error) {
  if (std::string message = options.validate(); !message.empty()) {
    setError(error, "scatter plot: " + message);
    return std::nullopt;
  }
  if (points.empty()) {
    setError(error, "scatter plot: no point");
    return std::nullopt;
  }
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
  for (const ScatterPoint& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
      setError(error, "scatter plot: point '" + p.label + "' is not finite");
      return std::nullopt;
    }
    if (p.series < 0) {
      setError(error, "scatter plot: point '" + p.label + "' has a negative series");
      return std::nullopt;
    }
    x_lo = std::min(x_lo, p.x);
    x_hi = std::max(x_hi, p.x);
    y_lo = std::min(y_lo, p.y);
    y_hi = std::max(y_hi, p.y);
  }
  const int top = options.title.empty() ? 16 : 40;
  const cv::Rect area(80, top, options.width - 110, options.height - top - 55);
  const Axis ax = makeAxis(x_lo, x_hi, area.x, area.x + area.width - 1);
  const Axis ay = makeAxis(y_lo, y_hi, area.y + area.height - 1, area.y);

  ColorImage image(options.width, options.height, Color{255, 255, 255});
  cv::Mat view(image.height, image.width, CV_8UC3, image.data.data());
  const int x_target = std::max(2, area.width / 110);
  const std::vector<double> x_ticks = niceTicks(ax.min, ax.max, x_target);
  const std::vector<double> y_ticks = niceTicks(ay.min, ay.max, std::max(2, area.height / 80));
  const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1.0;
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1.0;
  for (const double t : x_ticks) {
    const int u = static_cast<int>(std::lround(ax(t)));
    cv::line(view, cv::Point(u, area.y), cv::Point(u, area.y + area.height - 1), kGrid, 1);
    const std::string label = formatTick(t, x_step);
    text(view, label,
         cv::Point(u - textSize(label, kLabelScale).width / 2, area.y + area.height + 18),
         kLabelScale);
  }
  for (const double t : y_ticks) {
    const int v = static_cast<int>(std::lround(ay(t)));
    cv::line(view, cv::Point(area.x, v), cv::Point(area.x + area.width - 1, v), kGrid, 1);
    const std::string label = formatTick(t, y_step);
    const cv::Size size = textSize(label, kLabelScale);
    text(view, label, cv::Point(area.x - 6 - size.width, v + size.height / 2), kLabelScale);
  }
  cv::rectangle(view, area, kBlack, 1);
  const cv::Size x_size = textSize(options.x_label, kLabelScale);
  text(view, options.x_label,
       cv::Point(area.x + (area.width - x_size.width) / 2, area.y + area.height + 42), kLabelScale);
  text(view, options.y_label, cv::Point(8, std::max(12, area.y - 6)), kLabelScale);

  auto colour = [](int series) {
    return kSeriesColors[static_cast<size_t>(series) % kSeriesColors.size()];
  };
  auto pixel = [&](const ScatterPoint& p) {
    return cv::Point(static_cast<int>(std::lround(ax(p.x))),
                     static_cast<int>(std::lround(ay(p.y))));
  };
  if (options.join_series) {
    std::map<int, std::vector<const ScatterPoint*>> series;
    for (const ScatterPoint& p : points) {
      if (p.series >= 1) series[p.series].push_back(&p);
    }
    for (auto& [s, members] : series) {
      std::sort(members.begin(), members.end(),
                [](const ScatterPoint* a, const ScatterPoint* b) { return a->x < b->x; });
      for (size_t k = 1; k < members.size(); ++k) {
        cv::line(view, pixel(*members[k - 1]), pixel(*members[k]), colour(s), 2, cv::LINE_AA);
      }
    }
  }
  for (const ScatterPoint& p : points) {
    const cv::Point c = pixel(p);
    cv::circle(view, c, 6, colour(p.series), cv::FILLED, cv::LINE_AA);
    cv::circle(view, c, 6, kBlack, 1, cv::LINE_AA);
    if (!p.label.empty()) text(view, p.label, cv::Point(c.x + 9, c.y - 6), kLabelScale);
  }
  if (!options.title.empty()) {
    const cv::Size size = textSize(options.title, kTitleScale);
    cv::putText(view, options.title, cv::Point((options.width - size.width) / 2, 26), kFont,
                kTitleScale, kBlack, 1, cv::LINE_AA);
  }
  return image;
}

bool writeScatterPlotPng(const std::string& path, const std::vector<ScatterPoint>& points,
                         const ScatterPlotConfig& options, std::string* error) {
  const std::optional<ColorImage> image = renderScatterPlot(points, options, error);
  if (!image) return false;
  return writeColorImagePng(path, *image, error);
}

}  // namespace cblox
