#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace cblox {

/// Logs bad-input problems "once per kind with rate limiting": the first occurrence of a kind
/// is logged at once; later ones of the same kind are counted and summarised at most once per
/// `interval` ("... (N more since the last message)"). Kinds are small integers [0, num_kinds).
///
/// Thread-safety: every member function is thread-safe (one mutex; the sink is called with
/// it held, so the sink must not call back into this object).
class RateLimitedLog {
 public:
  using Clock = std::chrono::steady_clock;
  using Sink = std::function<void(const std::string&)>;

  RateLimitedLog(size_t num_kinds, Clock::duration interval, Sink sink)
      : interval_(interval), sink_(std::move(sink)), kinds_(num_kinds) {}

  /// Reports one occurrence of `kind` with its message; returns true when it was written to
  /// the sink (false: suppressed and counted). Out-of-range kinds are logged unconditionally.
  bool report(size_t kind, const std::string& message, Clock::time_point now = Clock::now()) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (kind >= kinds_.size()) {
      if (sink_) sink_(message);
      return true;
    }
    State& state = kinds_[kind];
    if (state.logged_once && now - state.last_logged < interval_) {
      ++state.suppressed;
      return false;
    }
    std::string line = message;
    if (state.suppressed > 0) {
      line += " (" + std::to_string(state.suppressed) + " more since the last message)";
    }
    state.logged_once = true;
    state.last_logged = now;
    state.suppressed = 0;
    if (sink_) sink_(line);
    return true;
  }

 private:
  struct State {
    bool logged_once = false;
    Clock::time_point last_logged{};
    uint64_t suppressed = 0;
  };
  const Clock::duration interval_;
  const Sink sink_;
  std::mutex mutex_;
  std::vector<State> kinds_;
};

}  // namespace cblox
