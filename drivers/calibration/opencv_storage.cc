#include "drivers/calibration/opencv_storage.h"

#include <fstream>
#include <iterator>

namespace cblox {

cv::FileStorage openOpenCvStorage(const std::string& path, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot open";
    return {};
  }
  size_t offset = 0;
  for (std::istreambuf_iterator<char> it(in), end; it != end; ++it, ++offset) {
    if (*it == '\0') {
      *error = path + ": NUL byte at offset " + std::to_string(offset) +
               ": binary data, not an OpenCV YAML/XML text file";
      return {};
    }
  }
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ);
    if (!fs.isOpened()) *error = path + ": cannot parse as OpenCV YAML/XML";
    return fs;
  } catch (const cv::Exception& e) {
    *error = path + ": cannot parse as OpenCV YAML/XML: " + e.msg;
    return {};
  }
}

}  // namespace cblox
