#pragma once

// Tiny image files for the dataset fuzz targets: the input gives a dataset's text files, the
// target adds the images they name in the seeds, so that a folder the fuzzer keeps valid is
// read to the end (frames decoded, rectified, checked against the intrinsics).

#include <string>

namespace cblox::fuzz {

/// Width and height of every tiny image (the seeds' calibrations say so too).
inline constexpr int kTinyImageWidth = 32;
inline constexpr int kTinyImageHeight = 24;

enum class TinyImage { kGray8, kColor8, kDepth16 };

/// Writes a PNG of kTinyImageWidth x kTinyImageHeight of that kind (a smooth pattern, depth
/// 1000..2000 mm) to `dir`/`relative`, creating the folders. Throws std::runtime_error when
/// it cannot. Not thread-safe (caches the encoded bytes).
void writeTinyImage(const std::string& dir, const std::string& relative, TinyImage kind);

}  // namespace cblox::fuzz
