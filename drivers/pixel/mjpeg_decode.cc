#include "drivers/pixel/mjpeg_decode.h"

#include <turbojpeg.h>

#include <memory>
#include <string>

namespace cblox {
namespace {

static_assert(sizeof(unsigned long) >= sizeof(size_t), "JPEG sizes pass as unsigned long");

struct TjDeleter {
  void operator()(void* handle) const { tjDestroy(handle); }
};
using TjHandle = std::unique_ptr<void, TjDeleter>;

std::string describe(const RawImage& raw) {
  return "MJPEG " + std::to_string(raw.width) + "x" + std::to_string(raw.height);
}

ConvertResult decodeFailed(const RawImage& raw, const std::string& what, tjhandle handle) {
  std::string message = describe(raw) + ": " + what;
  if (handle != nullptr) {
    message += ": ";
    message += tjGetErrorStr2(handle);
  }
  return ConvertResult{ConvertError::kDecodeFailed, std::move(message)};
}

}  // namespace

ConvertResult decodeMjpeg(const RawImage& raw, JpegOutput output, std::vector<uint8_t>* pixels) {
  TjHandle handle(tjInitDecompress());
  if (!handle) return decodeFailed(raw, "cannot create a libjpeg-turbo decoder", nullptr);
  // libjpeg-turbo's API takes a non-const pointer but only reads the stream.
  auto* stream = const_cast<unsigned char*>(raw.data);
  const auto size = static_cast<unsigned long>(raw.bytes);
  int width = 0;
  int height = 0;
  int subsampling = 0;
  int colorspace = 0;
  if (tjDecompressHeader3(handle.get(), stream, size, &width, &height, &subsampling, &colorspace) !=
      0) {
    return decodeFailed(raw, "bad JPEG header", handle.get());
  }
  if (width != raw.width || height != raw.height) {
    return ConvertResult{ConvertError::kDecodeFailed,
                         describe(raw) + ": JPEG stream is " + std::to_string(width) + "x" +
                             std::to_string(height) + ", not the announced size"};
  }
  const int channels = output == JpegOutput::kGray ? 1 : 3;
  const int pixel_format = output == JpegOutput::kGray ? TJPF_GRAY : TJPF_RGB;
  pixels->resize(static_cast<size_t>(width) * static_cast<size_t>(height) *
                 static_cast<size_t>(channels));
  if (tjDecompress2(handle.get(), stream, size, pixels->data(), width, width * channels, height,
                    pixel_format, TJFLAG_STOPONWARNING) != 0) {
    return decodeFailed(raw, "corrupt JPEG data", handle.get());
  }
  return {};
}

}  // namespace cblox
