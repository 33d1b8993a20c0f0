#pragma once

// The one CBLOX_HEARTBEAT builder every process uses: process name, pid, state and named
// counters, plus the process's own CPU time and resident memory read from /proc.

#include <cstdint>
#include <string>
#include <utility>

#include <cblox/heartbeat_t.hpp>

namespace cblox {

/// CPU time (user + system, all threads) and resident set of this process, read from
/// /proc/self/stat and /proc/self/statm. Zero where /proc cannot be read. Thread-safe.
struct ProcessUsage {
  int64_t cpu_ms = 0;
  int64_t rss_kib = 0;
  static ProcessUsage current();
};

/// Builds one heartbeat_t. Not thread-safe (one builder per heartbeat; cheap to make).
class HeartbeatBuilder {
 public:
  HeartbeatBuilder(std::string process, std::string state);

  /// Appends counter `name` = `value` (values above INT64_MAX saturate).
  HeartbeatBuilder& add(const std::string& name, uint64_t value);
  HeartbeatBuilder& add(const std::string& name, int64_t value);
  /// Appends a duration given in milliseconds as whole microseconds (`name` ends in _us).
  HeartbeatBuilder& addMicroseconds(const std::string& name, double ms);

  /// The state given to the constructor, or the last setState().
  const std::string& state() const { return msg_.state; }
  /// Replaces the state (e.g. InputWatch::addTo puts the input silence before it).
  HeartbeatBuilder& setState(std::string state) {
    msg_.state = std::move(state);
    return *this;
  }

  /// The message: utime now (wall clock), this pid, the state, the counters added, then
  /// "cpu_ms" and "rss_kib" of this process.
  heartbeat_t build() const;

 private:
  heartbeat_t msg_;
};

}  // namespace cblox
