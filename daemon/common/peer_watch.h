#pragma once

// A second instance of a process on the same bus: two mappers integrating the same frames
// and both answering every command, two trackers publishing competing poses. Every process
// publishes CBLOX_HEARTBEAT with its name and pid; PeerWatch listens to the heartbeats and
// notices another pid under its own process name. It logs one line when such a peer appears
// and one when it is gone, and adds to the heartbeat:
//   other_instances       peers heard within the last forget_after_s
//   other_instances_seen  distinct peers heard since start
// and, while a peer is there, puts "another cblox-mapper on this bus (pid 4242)" before the
// process's own state. Wire it with MessageGuard::setPeerWatch (heartbeats pass the wire
// check like any message).

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "daemon/common/heartbeat.h"

namespace cblox {

/// Thread-safety: every member function is thread-safe (one mutex; log lines are written
/// after it is released).
class PeerWatch {
 public:
  using Clock = std::chrono::steady_clock;
  using NowFn = std::function<Clock::time_point()>;
  using LogSink = std::function<void(const std::string&)>;

  /// `process` is this process's heartbeat name (e.g. "cblox-mapper") and `own_pid` its pid:
  /// heartbeats with that name and another pid are peers. A peer not heard for
  /// `forget_after_s` (> 0) seconds is gone. `log` receives the lines (default: stderr);
  /// `now` is the clock (tests inject their own).
  PeerWatch(std::string process, int32_t own_pid, double forget_after_s = 5.0,
            LogSink log = nullptr, NowFn now = nullptr);
  PeerWatch(const PeerWatch&) = delete;
  PeerWatch& operator=(const PeerWatch&) = delete;

  /// A heartbeat of `process` / `pid` arrived now (any process; only peers count).
  void onHeartbeat(const std::string& process, int32_t pid);

  /// The peers heard within forget_after_s, ascending; logs the ones gone since the last
  /// call ("<process>: the other <process> (pid N) is gone").
  std::vector<int32_t> peers();
  /// Distinct peers heard since start.
  uint64_t peersSeen() const;

  /// Adds other_instances and other_instances_seen, and the state prefix while a peer is
  /// there.
  void addTo(HeartbeatBuilder* heartbeat);

  const std::string& process() const { return process_; }

 private:
  const std::string process_;
  const int32_t own_pid_;
  const double forget_after_s_;
  const LogSink log_;
  const NowFn now_;
  mutable std::mutex mutex_;
  std::map<int32_t, Clock::time_point> last_heard_;  // peers present
  std::set<int32_t> seen_;
};

}  // namespace cblox
