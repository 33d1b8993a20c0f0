#include "core/persistence/zstd_blob.h"

#include <stdexcept>

#include <zstd.h>

#include "core/persistence/byte_codec.h"

namespace cblox {

using persistence_detail::ByteReader;
using persistence_detail::ByteWriter;

size_t maxZstdBlobLength(size_t compressed_bytes) {
  return 16 * compressed_bytes + (size_t{1} << 20);
}

void appendZstdBlob(std::string_view data, int level, std::string* out) {
  ByteWriter(out).u64(data.size());
  const size_t start = out->size();
  out->resize(start + ZSTD_compressBound(data.size()));
  const size_t size =
      ZSTD_compress(out->data() + start, out->size() - start, data.data(), data.size(), level);
  if (ZSTD_isError(size)) {
    throw std::runtime_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(size));
  }
  out->resize(start + size);
}

std::string readZstdBlob(std::string_view blob, std::string* out) {
  ByteReader reader(blob);
  uint64_t length = 0;
  if (!reader.u64(&length)) return "truncated before the compressed section";
  const std::string_view frame = blob.substr(reader.position());
  if (length > maxZstdBlobLength(frame.size())) {
    return "uncompressed length " + std::to_string(length) + " out of bounds for " +
           std::to_string(frame.size()) + " compressed bytes";
  }
  out->assign(static_cast<size_t>(length), '\0');
  const size_t size = ZSTD_decompress(out->data(), out->size(), frame.data(), frame.size());
  if (ZSTD_isError(size)) {
    return std::string("decompression error: ") + ZSTD_getErrorName(size);
  }
  if (size != length) {
    return "the compressed section holds " + std::to_string(size) + " bytes, not the " +
           std::to_string(length) + " its length says";
  }
  return {};
}

}  // namespace cblox
