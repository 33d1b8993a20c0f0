#pragma once

#include <optional>
#include <string>

#include "core/geometry/color.h"
#include "core/geometry/image.h"
#include "core/io/tum_trajectory.h"

namespace cblox {

/// Options of renderTrajectoryPlot() and writeTrajectoryPlotPng(). Plain value type.
struct TrajectoryPlotConfig {
  int width = 1000;   ///< pixels, in [200, 10000]
  int height = 800;   ///< pixels, in [150, 10000]
  std::string title;  ///< one line centred above the plot (e.g. "ATE RMSE 0.034 m"); none if empty
  std::string ground_truth_label = "ground truth";
  std::string estimate_label = "estimate";
  Color ground_truth_color{31, 119, 180};  ///< blue
  Color estimate_color{214, 39, 40};       ///< red
  int line_thickness = 2;                  ///< pixels, in [1, 20]

  /// Empty when valid, else a message naming the bad field. Thread-safe.
  std::string validate() const;
};

/// Renders a top view of the trajectories' positions: world x to the right, world y up (the
/// world is z-up; z is ignored), with equal scaling on both axes. White background; the plot
/// area (margins: 70 px left, 20 px right, 50 px below, 40 px above with a title and 16 px
/// without) holds, centred, the bounding box of all positions widened on each side by 5 % of
/// its larger side (a single position: a 1 m x 1 m box). Light-grey grid lines at "nice" multiples
/// of the same step on both axes (niceTicks(), about one line per 100 px), labelled in metres along
/// the bottom and the left, "x [m]" and "y [m]" axis names, a black frame. The ground truth is
/// drawn as an anti-aliased polyline in ground_truth_color, then `estimate` (may be empty; pass it
/// already aligned, e.g. with applyAlignment()) in estimate_color on top; each starts at a filled
/// circle of its colour with a black rim. A legend (line samples, labels and the start marker) sits
/// in the plot area's corner that covers the fewest positions. Returns std::nullopt with a message
/// when the options are invalid, the ground truth is empty, or a position is not finite.
/// Thread-safe (pure).
std::optional<ColorImage> renderTrajectoryPlot(const StampedTrajectory& ground_truth,
                                               const StampedTrajectory& estimate,
                                               const TrajectoryPlotConfig& options,
                                               std::string* error);

/// renderTrajectoryPlot() written as an 8-bit RGB PNG file to `path` (PNG whatever the file
/// extension). Returns false with a message (naming the path when writing fails) on the errors
/// of renderTrajectoryPlot() or when the file cannot be written. Thread-safe (no shared state;
/// concurrent writes to the same path race in the file system).
bool writeTrajectoryPlotPng(const std::string& path, const StampedTrajectory& ground_truth,
                            const StampedTrajectory& estimate, const TrajectoryPlotConfig& options,
                            std::string* error);

/// Writes `image` as an 8-bit RGB PNG file to `path` (PNG whatever the extension). Returns
/// false with a message naming the path when the image is empty or its data does not hold
/// width * height pixels, or the file cannot be written. Thread-safe (as above).
bool writeColorImagePng(const std::string& path, const ColorImage& image, std::string* error);

}  // namespace cblox
