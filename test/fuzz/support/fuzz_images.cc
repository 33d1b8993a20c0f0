// Tiny image files for the dataset fuzz targets (fuzz_images.h).

#include "test/fuzz/support/fuzz_images.h"

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test/fuzz/support/fuzz_files.h"

namespace cblox::fuzz {
namespace {

std::vector<uint8_t> encodeTiny(TinyImage kind) {
  const int type = kind == TinyImage::kGray8    ? CV_8UC1
                   : kind == TinyImage::kColor8 ? CV_8UC3
                                                : CV_16UC1;
  cv::Mat image(kTinyImageHeight, kTinyImageWidth, type);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const int v = (7 * x + 11 * y) % 256;
      if (kind == TinyImage::kGray8) image.at<uint8_t>(y, x) = static_cast<uint8_t>(v);
      if (kind == TinyImage::kColor8) image.at<cv::Vec3b>(y, x) = cv::Vec3b(v, 255 - v, v / 2);
      if (kind == TinyImage::kDepth16)
        image.at<uint16_t>(y, x) = static_cast<uint16_t>(1000 + 4 * v);
    }
  }
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("cannot encode a tiny PNG");
  return png;
}

}  // namespace

void writeTinyImage(const std::string& dir, const std::string& relative, TinyImage kind) {
  static std::array<std::vector<uint8_t>, 3> cache;
  std::vector<uint8_t>& png = cache[static_cast<size_t>(kind)];
  if (png.empty()) png = encodeTiny(kind);
  writeScratchFile(dir, relative,
                   std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

}  // namespace cblox::fuzz
