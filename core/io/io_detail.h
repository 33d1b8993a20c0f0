#pragma once

// Helpers shared by the file formats of cblox_io (OBJ, PLY): number formatting, reading a whole
// file, buffered writing. Internal to cblox_io: include only
// from its .cc files.

#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

namespace cblox::io_detail {

/// Appends `value` in the shortest form that reads back as the same float (std::to_chars).
/// Thread-safe (no shared state).
inline void appendFloatText(std::string* out, float value) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), value);  // shortest round-trip form
  out->append(buf, r.ptr);
}

/// Appends `value` in decimal. Thread-safe (no shared state).
inline void appendIntText(std::string* out, long long value) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof(buf), value);
  out->append(buf, r.ptr);
}

/// Reads the whole file at `path` (binary) into *data (non-null). Returns false, writing
/// "<path>: cannot open for reading: <reason>" or "<path>: read failed: <reason>" to *error (if
/// non-null), when it cannot be opened or read. Thread-safe (no shared state).
inline bool readWholeFile(const std::string& path, std::string* data, std::string* error) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    if (error != nullptr) *error = path + ": cannot open for reading: " + std::strerror(errno);
    return false;
  }
  data->assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
  if (file.bad()) {
    if (error != nullptr) *error = path + ": read failed: " + std::strerror(errno);
    return false;
  }
  return true;
}

/// Writes a file through an in-memory buffer: callers append to buffer() and call flushIfFull()
/// now and then, so at most about 1 MiB is held. Not thread-safe.
class BufferedFileWriter {
 public:
  /// Opens `path` for writing (binary, truncated). Returns false, writing
  /// "<path>: cannot open for writing: <reason>" to *error (if non-null), if it cannot.
  bool open(const std::string& path, std::string* error) {
    path_ = path;
    file_.open(path, std::ios::binary | std::ios::trunc);
    if (!file_) {
      if (error != nullptr) *error = path + ": cannot open for writing: " + std::strerror(errno);
      return false;
    }
    return true;
  }

  /// What is still to be written; append to it.
  std::string& buffer() { return buffer_; }

  /// False once a write has failed.
  bool good() const { return static_cast<bool>(file_); }

  /// Writes the buffer out if it holds 1 MiB or more. Returns false if that write failed.
  bool flushIfFull() { return buffer_.size() < kFlushBytes || flush(); }

  /// Writes the rest of the buffer (unless a write failed before) and closes the file. Returns
  /// false, writing "<path>: write failed: <reason>" to *error (if non-null), if any write or
  /// the close failed.
  bool close(std::string* error) {
    if (file_) flush();
    file_.close();
    if (!file_) {
      if (error != nullptr) *error = path_ + ": write failed: " + std::strerror(errno);
      return false;
    }
    return true;
  }

 private:
  static constexpr size_t kFlushBytes = size_t{1} << 20;

  bool flush() {
    file_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
    return static_cast<bool>(file_);
  }

  std::string path_;
  std::ofstream file_;
  std::string buffer_;
};

}  // namespace cblox::io_detail
