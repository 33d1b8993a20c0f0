#pragma once

#include <string>
#include <vector>

#include "core/geometry/color.h"
#include "core/geometry/image.h"

namespace cblox {

/// Viridis (the perceptually uniform matplotlib default, as tabulated by OpenCV's
/// cv::COLORMAP_VIRIDIS: 256 sRGB entries) at t in [0, 1], linearly interpolated between the
/// entries and rounded. t = 0 gives dark purple (68, 1, 84), t = 1 yellow (253, 231, 37);
/// luminance increases with t (strictly between values 1/50 apart; 8-bit rounding makes it
/// dip by < 1e-3 between a few neighbouring entries), so it reads in grey scale too. t outside [0,
/// 1] is clamped; NaN gives the colour of 0. Thread-safe (the table is built once, on first use,
/// and never changed).
Color colormap(double t);

/// About `target_count` "nice" tick values (multiples of 1, 2 or 5 times a power of ten) in
/// [min_value, max_value], increasing; ends that fall between ticks are not included. Empty
/// when the range is not finite or max_value <= min_value; target_count < 1 counts as 1.
/// Thread-safe (pure).
std::vector<double> niceTicks(double min_value, double max_value, int target_count);

/// `value` as text ("%.*f") with the fewest decimals that write the tick spacing `step`
/// exactly (0 for step 1 or 20, 1 for 0.5, 2 for 0.05 or 0.25, ...; at most 9; 0 when step
/// is not finite or <= 0); values within 1e-9 * step of zero are written as 0 (never "-0").
/// Thread-safe (pure).
std::string formatTick(double value, double step);

/// Draws a vertical colour bar into `image`: the rectangle of `width` x `height` pixels with
/// its top-left corner at column x, row y is filled with colormap(), max_value at the top row
/// and min_value at the bottom row, inside a 1-pixel black frame (around the rectangle). Ticks
/// (niceTicks(min_value, max_value, 5)) are marked by 4-pixel lines to the right of the frame
/// and labelled to the right of those (about 60 pixels wide in total); `unit` (may be empty) is
/// written about 8 pixels above the frame. Labels are black, OpenCV Hershey simplex font
/// (scale 0.4, anti-aliased). If max_value <= min_value or either is not finite the bar is
/// drawn with a single label, min_value, at the bottom. Everything is clipped to the image;
/// nothing is drawn when image is null or empty, width or height is < 1, or image->data does
/// not hold width * height pixels. Thread-safe for distinct images.
void drawColorBar(ColorImage* image, int x, int y, int width, int height, double min_value,
                  double max_value, const std::string& unit);

}  // namespace cblox
