#pragma once

// Counts frames a camera source had to drop, by kind, and reports the first of each kind.

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>

namespace cblox {

/// Dropped frames by kind ("corrupt", "short_buffer", "decode_failed", "stall",
/// "left_unpaired", ...). The first drop of each kind is reported to the sink (stderr by
/// default) with its message and a note that later ones are only counted. Not thread-safe:
/// one thread uses it.
class DropCounter {
 public:
  using Sink = std::function<void(const std::string& line)>;

  /// `prefix` starts each reported line, e.g. "v4l2:/dev/video0". A null sink discards.
  explicit DropCounter(std::string prefix, Sink sink = writeToStderr);

  /// Counts one drop of `kind`; reports `message` if it is the first of its kind.
  void count(std::string_view kind, const std::string& message);

  /// Count of `kind` (0 if never seen).
  int64_t count(std::string_view kind) const;

  /// Every kind seen and its count, sorted by kind.
  const std::map<std::string, int64_t, std::less<>>& counts() const { return counts_; }

  /// Sum over all kinds.
  int64_t total() const;

  /// "corrupt=2 stall=1" (sorted by kind), or "none". Thread-safe with other const calls.
  std::string summary() const;

  /// Writes `line` and a newline to stderr. Thread-safe.
  static void writeToStderr(const std::string& line);

 private:
  std::string prefix_;
  Sink sink_;
  std::map<std::string, int64_t, std::less<>> counts_;
};

}  // namespace cblox
