#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace cblox {

/// Resolves a path an operator asked for (e.g. in an export command) inside the configured
/// output directory: a relative path is taken relative to it; an absolute path is accepted
/// only if it lies inside it. Rejected, with a message: an empty path, any ".." component,
/// a NUL character, an absolute path outside the directory. The result is lexically
/// normalised; nothing is created or checked on disk. Thread-safe (pure).
std::optional<std::filesystem::path> resolveOutputPath(const std::filesystem::path& output_dir,
                                                       const std::string& requested,
                                                       std::string* error);

/// Checks on disk that `target` (a path resolveOutputPath returned) really lies inside
/// `output_dir` once symbolic links are followed: the longest existing prefix of `target` is
/// resolved (std::filesystem::weakly_canonical) and must be inside canonical(output_dir).
/// Returns false with a message when a link leads outside or output_dir does not exist.
/// Call it right before writing. Thread-safe (reads the file system only).
bool staysInsideOnDisk(const std::filesystem::path& output_dir,
                       const std::filesystem::path& target, std::string* error);

/// resolveOutputPath, then staysInsideOnDisk: the path to write to right now, or std::nullopt
/// with the first refusal's message. Thread-safe (reads the file system only).
std::optional<std::filesystem::path> writableOutputPath(const std::filesystem::path& output_dir,
                                                        const std::string& requested,
                                                        std::string* error);

}  // namespace cblox
