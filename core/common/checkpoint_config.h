#pragma once

// The `checkpoint` part of config/mapper.yaml and config/tracker.yaml: periodic checkpoints
// of a process's map into a directory, and resume from it at start.

#include <cmath>
#include <string>

namespace cblox {

/// Periodic checkpoints and resume at start. Plain value type.
struct CheckpointConfig {
  /// The checkpoint directory (any path, not confined to output_dir; created by the first
  /// checkpoint). Empty = no checkpoints and no resume. With a directory, a clean stop always
  /// writes a last checkpoint.
  std::string dir;
  /// A checkpoint every this many seconds on a low-priority thread (finite, >= 0); 0 = only
  /// the last one of a clean stop. A kill loses at most this much.
  double period_s = 30.0;
  /// At start, load the checkpoint in `dir` when there is one; a checkpoint that cannot be
  /// loaded is a configuration error (exit 2), never silently replaced by an empty map.
  bool resume = true;

  /// Checkpoints are written (dir set): at a clean stop, and every period_s when > 0.
  bool enabled() const { return !dir.empty(); }
  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const {
    if (!(period_s >= 0.0) || !std::isfinite(period_s)) {
      return "period_s must be finite and >= 0, got " + std::to_string(period_s);
    }
    return {};
  }
};

}  // namespace cblox
