#include "drivers/v4l2/v4l2_formats.h"

#include <cstdio>

#include "drivers/pixel/pixel_format.h"

namespace cblox {
namespace {

std::string describeSize(const V4l2FrameSize& size) {
  std::string text;
  if (size.stepwise) {
    text = std::to_string(size.min_width) + "x" + std::to_string(size.min_height) + "..";
  }
  text += std::to_string(size.width) + "x" + std::to_string(size.height);
  if (size.stepwise && (size.step_width != 1 || size.step_height != 1)) {
    text += " step " + std::to_string(size.step_width) + "x" + std::to_string(size.step_height);
  }
  if (!size.rates_hz.empty()) {
    text += " @ ";
    for (size_t i = 0; i < size.rates_hz.size(); ++i) {
      if (i > 0) text += '/';
      text += formatRateHz(size.rates_hz[i]);
    }
    text += " Hz";
  } else if (size.max_rate_hz > 0.0) {
    text += " @ " + formatRateHz(size.min_rate_hz) + "-" + formatRateHz(size.max_rate_hz) + " Hz";
  }
  return text;
}

}  // namespace

std::string formatRateHz(double rate_hz) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", rate_hz);
  std::string s = text;
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

std::string describeFormats(const std::vector<V4l2FormatInfo>& formats) {
  if (formats.empty()) return "(no formats)";
  std::string text;
  for (const V4l2FormatInfo& format : formats) {
    if (!text.empty()) text += '\n';
    text += fourccToString(format.fourcc) + " (" + format.description;
    if (format.compressed) text += ", compressed";
    if (format.emulated) text += ", emulated";
    if (!pixelFormatFromFourcc(format.fourcc)) text += ", not supported by cblox";
    text += "):";
    for (size_t i = 0; i < format.sizes.size(); ++i) {
      text += i == 0 ? " " : ", ";
      text += describeSize(format.sizes[i]);
    }
    if (format.sizes.empty()) text += " (sizes not listed)";
  }
  return text;
}

}  // namespace cblox
