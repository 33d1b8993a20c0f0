#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/geometry/color.h"
#include "core/geometry/image.h"

namespace cblox {

/// One labelled point of a scatter plot. `series` picks its colour and whether it is joined
/// to the other points of its series (see ScatterPlotConfig). Plain value type.
struct ScatterPoint {
  double x = 0.0;
  double y = 0.0;
  std::string label;  ///< written next to the marker (none if empty)
  int series = 0;     ///< >= 0
};

/// Options of renderScatterPlot(). Plain value type.
struct ScatterPlotConfig {
  int width = 1000;   ///< pixels, in [200, 10000]
  int height = 700;   ///< pixels, in [150, 10000]
  std::string title;  ///< one centred line above the plot; none if empty
  std::string x_label, y_label;
  /// Series s >= 1 are joined by a line in increasing x (a sweep); series 0 points stand alone.
  bool join_series = true;

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// Renders the points on a white background: the plot area (margins 80 px left, 30 px right,
/// 55 px below, 40 px above with a title and 16 px without) holds the bounding box of the
/// points (both axes start at zero when all values are positive, so ratios read true), widened
/// by 8 % of each span (1 for a zero span); light-grey grid lines at niceTicks() values,
/// labelled along the bottom and the left, the axis names, a black frame. Each point is a
/// filled circle (radius 6 px, black rim) in its series' colour (series 0 grey-blue, series 1
/// red, then other tab10 colours), with its label to its right. Returns std::nullopt with a
/// message for invalid options, no point, a non-finite coordinate or a negative series.
/// Thread-safe (pure).
std::optional<ColorImage> renderScatterPlot(const std::vector<ScatterPoint>& points,
                                            const ScatterPlotConfig& options, std::string* error);

/// renderScatterPlot() written as a PNG (writeColorImagePng). False with a message on its
/// errors or when the file cannot be written. Thread-safe (no shared state).
bool writeScatterPlotPng(const std::string& path, const std::vector<ScatterPoint>& points,
                         const ScatterPlotConfig& options, std::string* error);

}  // namespace cblox
