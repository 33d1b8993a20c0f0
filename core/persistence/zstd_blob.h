#pragma once

// One zstd frame holding a whole payload, with the uncompressed length stored in front and
// bounded before anything is allocated: the compressed sections of the tracker's map files
// (sparse_map_file.h). The submap files stream their blocks instead (submap_file.cc).

#include <string>
#include <string_view>

namespace cblox {

/// Largest uncompressed length accepted for `compressed_bytes` of zstd: 16 x + 1 MiB. Real
/// sections (descriptors, poses) compress by well under 2 x; a forged length beyond this is
/// refused instead of allocated.
size_t maxZstdBlobLength(size_t compressed_bytes);

/// Appends uint64 uncompressed length + one zstd frame (level `level`) of `data` to *out.
/// Throws std::runtime_error if zstd fails. Thread-safe (no shared state).
void appendZstdBlob(std::string_view data, int level, std::string* out);

/// Reads what appendZstdBlob wrote, taking all of `blob`: checks the stored length against
/// maxZstdBlobLength before allocating, decompresses, and checks that the frame fills exactly
/// that length. Returns an empty string on success, else what is wrong. Thread-safe.
std::string readZstdBlob(std::string_view blob, std::string* out);

}  // namespace cblox
