#pragma once

// Files for the fuzz targets whose parser reads a path, not bytes: a private scratch
// directory per process, emptied before every input, and the input split into the several
// files a reader opens together (a dataset folder, a map directory).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace cblox::fuzz {

/// Separates the files of one input (the seeds are readable text): "\n@@@@\n".
inline constexpr std::string_view kPartSeparator = "\n@@@@\n";

/// The input split at every kPartSeparator; always `count` parts (missing ones empty, the
/// last one takes the rest, separators included). Thread-safe (pure).
std::vector<std::string> splitParts(const uint8_t* data, size_t size, size_t count);

/// The process's scratch directory (created on first use under $TMPDIR or /tmp, removed at
/// exit), emptied of everything an earlier input left. Not thread-safe (one fuzzer thread).
const std::string& freshScratchDir();

/// Writes `bytes` to `dir`/`relative`, creating the parent folders. Throws std::runtime_error
/// when the file cannot be written (the scratch directory is broken: not the input's fault).
void writeScratchFile(const std::string& dir, const std::string& relative, std::string_view bytes);

}  // namespace cblox::fuzz
