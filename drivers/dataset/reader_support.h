#pragma once

// Small helpers shared by the dataset readers: error reporting and file-system checks that never
// throw. Internal to cblox_dataset.

#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace cblox::dataset_detail {

/// Writes `message` to *error if error is non-null and returns false, for
/// `return setError(error, ...);`. Thread-safe (no shared state).
inline bool setError(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

/// True if `path` names an existing regular file; never throws. Thread-safe.
inline bool isFile(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

/// True if `path` names an existing directory; never throws. Thread-safe.
inline bool isDirectory(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec);
}

/// `b` inside folder `a`: "a/b". Thread-safe (no shared state).
inline std::string join(const std::string& a, const std::string& b) {
  return (std::filesystem::path(a) / b).string();
}

/// "<path>:<line>: ", the start of a message about one line of a file. Thread-safe (no shared
/// state).
inline std::string at(const std::string& path, size_t line) {
  return path + ":" + std::to_string(line) + ": ";
}

/// Parses a finite double; the whole text must be the number. Thread-safe (no shared state).
inline bool parseDouble(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(*value);
}

}  // namespace cblox::dataset_detail
