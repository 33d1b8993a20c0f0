#include "core/eval/trajectory_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/eval/colormap.h"

namespace cblox {
namespace {

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kLabelScale = 0.45;
constexpr double kTitleScale = 0.6;
constexpr int kShift = 4;  // polyline coordinates in 1/16 pixel
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(225, 225, 225);
const cv::Scalar kText(40, 40, 40);

cv::Scalar scalar(const Color& c) { return cv::Scalar(c.r, c.g, c.b); }  // the view is RGB

// Positions as world (x, y); false if one is not finite.
bool topView(const StampedTrajectory& trajectory, const char* name, std::vector<cv::Point2d>* xy,
             std::string* error) {
  xy->reserve(trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const Eigen::Vector3d& p = trajectory[i].T_G_C.translation();
    if (!p.allFinite()) {
      setError(error, std::string("trajectory plot: ") + name + " position " + std::to_string(i) +
                          " is not finite");
      return false;
    }
    xy->emplace_back(p.x(), p.y());
  }
  return true;
}

// World (x, y) to pixel coordinates, equal scale, y up.
struct Projection {
  cv::Rect area;
  double center_x = 0.0;
  double center_y = 0.0;
  double pixels_per_metre = 1.0;

  cv::Point2d operator()(const cv::Point2d& p) const {
    return {area.x + 0.5 * area.width + (p.x - center_x) * pixels_per_metre,
            area.y + 0.5 * area.height - (p.y - center_y) * pixels_per_metre};
  }
  double worldX(double u) const {
    return center_x + (u - area.x - 0.5 * area.width) / pixels_per_metre;
  }
  double worldY(double v) const {
    return center_y - (v - area.y - 0.5 * area.height) / pixels_per_metre;
  }
};

cv::Point fixedPoint(const cv::Point2d& p) {
  return cv::Point(static_cast<int>(std::lround(p.x * (1 << kShift))),
                   static_cast<int>(std::lround(p.y * (1 << kShift))));
}

void drawPolyline(cv::Mat& view, const Projection& project, const std::vector<cv::Point2d>& xy,
                  const Color& color, int thickness) {
  if (xy.empty()) return;
  std::vector<cv::Point> points;
  points.reserve(xy.size());
  for (const cv::Point2d& p : xy) points.push_back(fixedPoint(project(p)));
  if (points.size() == 1) points.push_back(points.front());
  cv::polylines(view, std::vector<std::vector<cv::Point>>{points}, false, scalar(color), thickness,
                cv::LINE_AA, kShift);
}

void drawStartMarker(cv::Mat& view, const cv::Point2d& pixel, const cv::Scalar& fill) {
  const cv::Point center = fixedPoint(pixel);
  constexpr int kRadius = 6 << kShift;
  cv::circle(view, center, kRadius, fill, cv::FILLED, cv::LINE_AA, kShift);
  cv::circle(view, center, kRadius, kBlack, 1, cv::LINE_AA, kShift);
}

void putText(cv::Mat& view, const std::string& text, cv::Point origin, double scale) {
  cv::putText(view, text, origin, kFont, scale, kText, 1, cv::LINE_AA);
}

cv::Size textSize(const std::string& text, double scale) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, 1, &baseline);
}

void drawGrid(cv::Mat& view, const Projection& project) {
  const cv::Rect& area = project.area;
  const double x_min = project.worldX(area.x);
  const double x_max = project.worldX(area.x + area.width);
  const double y_min = project.worldY(area.y + area.height);
  const double y_max = project.worldY(area.y);
  const int target =
      std::max(2, static_cast<int>(std::lround(std::max(area.width, area.height) / 100.0)));
  const std::vector<double> ticks = niceTicks(0.0, std::max(x_max - x_min, y_max - y_min), target);
  if (ticks.size() < 2) return;
  const double step = ticks[1] - ticks[0];
  for (double k = std::ceil(x_min / step); k * step <= x_max; k += 1.0) {
    const int u = static_cast<int>(std::lround(project({k * step, 0.0}).x));
    cv::line(view, cv::Point(u, area.y), cv::Point(u, area.y + area.height - 1), kGrid, 1);
    const std::string label = formatTick(k * step, step);
    const cv::Size size = textSize(label, kLabelScale);
    putText(view, label, cv::Point(u - size.width / 2, area.y + area.height + 18), kLabelScale);
  }
  for (double k = std::ceil(y_min / step); k * step <= y_max; k += 1.0) {
    const int v = static_cast<int>(std::lround(project({0.0, k * step}).y));
    cv::line(view, cv::Point(area.x, v), cv::Point(area.x + area.width - 1, v), kGrid, 1);
    const std::string label = formatTick(k * step, step);
    const cv::Size size = textSize(label, kLabelScale);
    putText(view, label, cv::Point(area.x - 6 - size.width, v + size.height / 2), kLabelScale);
  }
  const cv::Size x_size = textSize("x [m]", kLabelScale);
  putText(view, "x [m]",
          cv::Point(area.x + (area.width - x_size.width) / 2, area.y + area.height + 40),
          kLabelScale);
  putText(view, "y [m]", cv::Point(std::max(2, area.x - 64), std::max(12, area.y - 5)),
          kLabelScale);
}

struct LegendEntry {
  std::string label;
  cv::Scalar color;
  bool marker;  // start marker instead of a line sample
};

void drawLegend(cv::Mat& view, const Projection& project, const std::vector<LegendEntry>& entries,
                const std::vector<cv::Point2d>& pixels) {
  constexpr int kPad = 8;
  constexpr int kSample = 30;
  constexpr int kRow = 20;
  int text_width = 0;
  for (const LegendEntry& e : entries) {
    text_width = std::max(text_width, textSize(e.label, kLabelScale).width);
  }
  const cv::Size box(2 * kPad + kSample + 8 + text_width,
                     2 * kPad + kRow * static_cast<int>(entries.size()) - 4);
  const cv::Rect& area = project.area;
  constexpr int kInset = 10;
  const int left = area.x + kInset;
  const int right = area.x + area.width - kInset - box.width;
  const int top = area.y + kInset;
  const int bottom = area.y + area.height - kInset - box.height;
  const std::array<cv::Point, 4> corners = {cv::Point(right, top), cv::Point(left, top),
                                            cv::Point(right, bottom), cv::Point(left, bottom)};
  cv::Rect best;
  size_t best_count = std::numeric_limits<size_t>::max();
  for (const cv::Point& corner : corners) {
    const cv::Rect candidate(corner, box);
    size_t count = 0;
    for (const cv::Point2d& p : pixels)
      count += candidate.contains(cv::Point(static_cast<int>(p.x), static_cast<int>(p.y))) ? 1 : 0;
    if (count < best_count) {
      best_count = count;
      best = candidate;
    }
  }
  cv::rectangle(view, best, cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(view, best, kBlack, 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const int v = best.y + kPad + static_cast<int>(i) * kRow + 6;
    const int u = best.x + kPad;
    if (entries[i].marker) {
      drawStartMarker(view, cv::Point2d(u + kSample / 2, v), entries[i].color);
    } else {
      cv::line(view, cv::Point(u, v), cv::Point(u + kSample, v), entries[i].color, 3, cv::LINE_8);
    }
    const cv::Size size = textSize(entries[i].label, kLabelScale);
    putText(view, entries[i].label, cv::Point(u + kSample + 8, v + size.height / 2), kLabelScale);
  }
}

}  // namespace

std::string TrajectoryPlotConfig::validate() const {
  if (width < 200 || width > 10000) {
    return "trajectory plot: width must be in [200, 10000] pixels, got " + std::to_string(width);
  }
  if (height < 150 || height > 10000) {
    return "trajectory plot: height must be in [150, 10000] pixels, got " + std::to_string(height);
  }
  if (line_thickness < 1 || line_thickness > 20) {
    return "trajectory plot: line_thickness must be in [1, 20] pixels, got " +
           std::to_string(line_thickness);
  }
  return "";
}

std::optional<ColorImage> renderTrajectoryPlot(const StampedTrajectory& ground_truth,
                                               const StampedTrajectory& estimate,
                                               const TrajectoryPlotConfig& options,
                                               std::string* error) {
  if (std::string message = options.validate(); !message.empty()) {
    setError(error, std::move(message));
    return std::nullopt;
  }
  if (ground_truth.empty()) {
    setError(error, "trajectory plot: the ground truth is empty");
    return std::nullopt;
  }
  std::vector<cv::Point2d> truth_xy;
  std::vector<cv::Point2d> estimate_xy;
  if (!topView(ground_truth, "ground truth", &truth_xy, error) ||
      !topView(estimate, "estimate", &estimate_xy, error)) {
    return std::nullopt;
  }

  // Bounding box of all positions, padded by 5 % of its larger side (1 m if it is a point).
  double x_min = std::numeric_limits<double>::infinity();
  double x_max = -x_min;
  double y_min = x_min;
  double y_max = -x_min;
  for (const auto* xy : {&truth_xy, &estimate_xy}) {
    for (const cv::Point2d& p : *xy) {
      x_min = std::min(x_min, p.x);
      x_max = std::max(x_max, p.x);
      y_min = std::min(y_min, p.y);
      y_max = std::max(y_max, p.y);
    }
  }
  const double extent = std::max(x_max - x_min, y_max - y_min);
  double span_x = x_max - x_min + 0.1 * extent;
  double span_y = y_max - y_min + 0.1 * extent;
  if (!(extent > 1e-9)) span_x = span_y = 1.0;
  if (!std::isfinite(span_x) || !std::isfinite(span_y)) {
    setError(error, "trajectory plot: the positions span more than a double can hold");
    return std::nullopt;
  }

  Projection project;
  const int top = options.title.empty() ? 16 : 40;
  project.area = cv::Rect(70, top, options.width - 90, options.height - top - 50);
  project.center_x = 0.5 * (x_min + x_max);
  project.center_y = 0.5 * (y_min + y_max);
  project.pixels_per_metre = std::min(project.area.width / span_x, project.area.height / span_y);

  ColorImage image(options.width, options.height, Color{255, 255, 255});
  cv::Mat view(image.height, image.width, CV_8UC3, image.data.data());  // RGB
  drawGrid(view, project);
  cv::rectangle(view, project.area, kBlack, 1);
  drawPolyline(view, project, truth_xy, options.ground_truth_color, options.line_thickness);
  drawPolyline(view, project, estimate_xy, options.estimate_color, options.line_thickness);
  drawStartMarker(view, project(truth_xy.front()), scalar(options.ground_truth_color));
  if (!estimate_xy.empty()) {
    drawStartMarker(view, project(estimate_xy.front()), scalar(options.estimate_color));
  }

  std::vector<LegendEntry> entries = {
      {options.ground_truth_label, scalar(options.ground_truth_color), false}};
  if (!estimate_xy.empty()) {
    entries.push_back({options.estimate_label, scalar(options.estimate_color), false});
  }
  entries.push_back({"start", cv::Scalar(255, 255, 255), true});
  std::vector<cv::Point2d> pixels;
  pixels.reserve(truth_xy.size() + estimate_xy.size());
  for (const auto* xy : {&truth_xy, &estimate_xy}) {
    for (const cv::Point2d& p : *xy) pixels.push_back(project(p));
  }
  drawLegend(view, project, entries, pixels);

  if (!options.title.empty()) {
    const cv::Size size = textSize(options.title, kTitleScale);
    cv::putText(view, options.title, cv::Point((options.width - size.width) / 2, 26), kFont,
                kTitleScale, kBlack, 1, cv::LINE_AA);
  }
  return image;
}

bool writeColorImagePng(const std::string& path, const ColorImage& image, std::string* error) {
  if (image.empty() ||
      image.data.size() != static_cast<size_t>(image.width) * static_cast<size_t>(image.height)) {
    setError(error, path + ": cannot write an empty or malformed image (" +
                        std::to_string(image.width) + "x" + std::to_string(image.height) + ", " +
                        std::to_string(image.data.size()) + " pixels)");
    return false;
  }
  static_assert(sizeof(Color) == 3, "Color must be 3 packed bytes to wrap it as CV_8UC3");
  const cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<Color*>(image.data.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<uchar> png;
  try {
    if (!cv::imencode(".png", bgr, png)) {
      setError(error, path + ": PNG encoding failed");
      return false;
    }
  } catch (const cv::Exception& e) {
    setError(error, path + ": PNG encoding failed: " + e.what());
    return false;
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) {
    setError(error, path + ": cannot open for writing");
    return false;
  }
  out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  out.close();
  if (!out) {
    setError(error, path + ": write failed");
    return false;
  }
  return true;
}

bool writeTrajectoryPlotPng(const std::string& path, const StampedTrajectory& ground_truth,
                            const StampedTrajectory& estimate, const TrajectoryPlotConfig& options,
                            std::string* error) {
  const std::optional<ColorImage> image =
      renderTrajectoryPlot(ground_truth, estimate, options, error);
  if (!image.has_value()) return false;
  return writeColorImagePng(path, *image, error);
}

}  // namespace cblox
