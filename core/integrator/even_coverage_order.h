#pragma once

#include <cstdint>
#include <vector>

namespace cblox {

/// The indices [0, n) in bit-reversed order (van der Corput sequence): any prefix of the
/// result is spread evenly over [0, n). For a row-major image or point cloud, a prefix
/// therefore samples rows and columns evenly, so a frame cut short by a time budget still
/// covers the whole image. Thread-safe (pure).
std::vector<uint32_t> evenCoverageOrder(uint32_t n);

}  // namespace cblox
