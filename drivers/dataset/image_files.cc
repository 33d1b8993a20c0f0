#include "drivers/dataset/image_files.h"

#include <opencv2/imgcodecs.hpp>

#include "drivers/dataset/reader_support.h"

namespace cblox {

using dataset_detail::isFile;
using dataset_detail::setError;

std::string describeImageType(const cv::Mat& image) {
  const int depth = image.depth();
  const int bits = depth == CV_8U || depth == CV_8S     ? 8
                   : depth == CV_16U || depth == CV_16S ? 16
                   : depth == CV_64F                    ? 64
                                                        : 32;
  return std::to_string(bits) + "-bit with " + std::to_string(image.channels()) + " channel(s)";
}

std::string describeSize(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

bool checkImageSize(const std::string& path, const cv::Mat& image, int width, int height,
                    const std::string& expected, std::string* error) {
  if (image.cols == width && image.rows == height) return true;
  return setError(error, path + ": size " + describeSize(image.cols, image.rows) +
                             " does not match " + expected + " " + describeSize(width, height));
}

bool readDepthUnits(const std::string& path, const std::string& requirement, cv::Mat* units,
                    std::string* error) {
  if (!isFile(path)) return setError(error, path + ": depth image is missing");
  *units = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (units->empty()) return setError(error, path + ": cannot read depth image");
  if (units->type() != CV_16UC1) {
    return setError(error, path + ": depth image must be " + requirement + ", got " +
                               describeImageType(*units));
  }
  return true;
}

DepthImage depthFromUnits(const cv::Mat& units, double metres_per_unit, uint16_t invalid_units) {
  DepthImage depth(units.cols, units.rows, 0.0f);
  for (int v = 0; v < units.rows; ++v) {
    const uint16_t* row = units.ptr<uint16_t>(v);
    for (int u = 0; u < units.cols; ++u) {
      const uint16_t d = row[u];
      depth(u, v) = (d == 0 || d == invalid_units) ? 0.0f : static_cast<float>(d * metres_per_unit);
    }
  }
  return depth;
}

ColorImage colorFromBgr(const cv::Mat& bgr) {
  ColorImage color(bgr.cols, bgr.rows);
  for (int v = 0; v < bgr.rows; ++v) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < bgr.cols; ++u) color(u, v) = Color{row[u][2], row[u][1], row[u][0]};
  }
  return color;
}

bool readGrayImage(const std::string& path, cv::Mat* image, std::string* error) {
  if (!isFile(path)) return setError(error, path + ": image is missing");
  *image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image->empty()) return setError(error, path + ": cannot read image");
  if (image->type() != CV_8UC1) {
    return setError(error, path + ": image must be 8-bit single-channel (grey), got " +
                               describeImageType(*image));
  }
  return true;
}

bool readColorImage(const std::string& path, int width, int height, const std::string& expected,
                    ColorImage* color, std::string* error) {
  if (!isFile(path)) return setError(error, path + ": colour image is missing");
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    return setError(error, path + ": cannot read colour image");
  }
  if (!checkImageSize(path, bgr, width, height, expected, error)) return false;
  *color = colorFromBgr(bgr);
  return true;
}

}  // namespace cblox
