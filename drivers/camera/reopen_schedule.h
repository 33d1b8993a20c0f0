#pragma once

// When to try reopening a camera that disappeared (unplugged, USB reset, driver crash):
// exponential back-off, pure arithmetic on injected times.

#include <cstdint>
#include <string>

namespace cblox {

/// Delay before reopen attempt `attempt` (1-based): min_s * 2^(attempt - 1), capped at
/// max_s; attempt < 1 counts as 1. Requires 0 < min_s <= max_s. Thread-safe (pure).
double reopenDelaySeconds(int attempt, double min_s, double max_s);

/// Now on std::chrono::steady_clock in nanoseconds: the clock the drivers give ReopenSchedule
/// and their frame deadlines. Thread-safe.
int64_t steadyNowNs();

/// "4" for 4.0, "0.5" for 0.5: seconds rounded up to a tenth, trailing zeros removed.
/// Thread-safe (pure).
std::string formatSeconds(double seconds);

/// State of a device between loss and recovery. Times are nanoseconds of any one clock the
/// caller keeps to (steady). After lost(), attempt 1 is due reopenDelaySeconds(1) later;
/// each failed() schedules the next attempt one (doubled, capped) delay after it failed;
/// succeeded() returns to connected. Not thread-safe: one thread uses it.
class ReopenSchedule {
 public:
  /// Requires 0 < min_s <= max_s (throws std::invalid_argument otherwise).
  ReopenSchedule(double min_s, double max_s);

  /// The device was lost at now_ns; a no-op if already reopening.
  void lost(int64_t now_ns);
  /// The pending attempt, made at now_ns, failed.
  void failed(int64_t now_ns);
  /// The pending attempt succeeded: connected again.
  void succeeded();

  bool reopening() const { return reopening_; }
  /// True if reopening and the pending attempt is due at now_ns.
  bool due(int64_t now_ns) const { return reopening_ && now_ns >= next_attempt_ns_; }
  /// Number (1-based) of the pending attempt; 0 when connected.
  int attempt() const { return reopening_ ? attempt_ : 0; }
  /// When the pending attempt is due (meaningful while reopening).
  int64_t nextAttemptNs() const { return next_attempt_ns_; }
  /// Attempts made (failed or succeeded) since construction.
  int64_t totalAttempts() const { return total_attempts_; }

  /// "" when connected, else "reopening <device> (attempt 3, next in 4 s)"; "next in 0 s"
  /// once due. Thread-safe with respect to other const calls.
  std::string status(const std::string& device, int64_t now_ns) const;

 private:
  double min_s_;
  double max_s_;
  bool reopening_ = false;
  int attempt_ = 0;
  int64_t next_attempt_ns_ = 0;
  int64_t total_attempts_ = 0;
};

}  // namespace cblox
