#pragma once

// The daemons' only way to subscribe to LCM channels. Any bytes may arrive on any channel (a
// bad log, another program, another message version): every message is checked against its
// type's wire layout before anything is allocated (lcmtypes/wire_check.h), decoded only
// then, and handed to the handler inside a try/catch. No message can end the process.

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/common/rate_limited_log.h"
#include "daemon/common/heartbeat.h"
#include "daemon/common/input_watch.h"
#include "daemon/common/peer_watch.h"
#include "lcmtypes/wire_check.h"

namespace cblox {

/// Counts of a MessageGuard since construction.
struct MessageGuardCounts {
  uint64_t accepted = 0;        ///< decoded and handed to a handler
  uint64_t handler_errors = 0;  ///< the handler threw (caught; the message is lost, not the process)
  std::array<uint64_t, static_cast<size_t>(WireError::kCount)> refused{};  ///< by WireError
  uint64_t refusedTotal() const;
};

/// Subscribes typed handlers to LCM channels behind the wire check.
///
/// A message that fails the check is counted by WireError kind, then either given to the
/// subscription's `on_refused` callback (which logs and counts it in the process's own terms)
/// or, without one, logged here once per kind with rate limiting. A handler that throws is
/// caught, counted as handler_errors and logged the same way.
///
/// With an InputWatch (setInputWatch), every message that passes the wire check on a channel
/// the watch watches is recorded as an arrival (input-silence health), whether or not its
/// handler then succeeds; refused messages are not input.
///
/// Thread-safety: subscribe() and setInputWatch() before the LCM thread starts handling; the
/// handlers run on the thread that calls lcm->handle*(); counts() and addTo() are thread-safe
/// (atomics; the InputWatch is thread-safe).
class MessageGuard {
 public:
  using LogSink = std::function<void(const std::string&)>;
  /// Called for a refused message with one line saying which channel, how many bytes and
  /// what was wrong, e.g. "CBLOX_DEPTH: message of 60 bytes refused (truncated): ...".
  using RefusedCallback = std::function<void(const std::string& description)>;

  /// `lcm` must outlive the guard. `log` receives the guard's own lines (default: stderr).
  MessageGuard(lcm::LCM* lcm, LogSink log = nullptr,
               std::chrono::steady_clock::duration log_interval = std::chrono::seconds(10));
  MessageGuard(const MessageGuard&) = delete;
  MessageGuard& operator=(const MessageGuard&) = delete;

  /// `handler(const Msg&, const std::string& channel)` for every message of `channel` that
  /// passes the wire check and decodes as Msg.
  template <typename Msg, typename Handler>
  void subscribe(const std::string& channel, Handler handler, RefusedCallback on_refused = nullptr) {
    auto entry = std::make_unique<Entry>();
    entry->guard = this;
    entry->on_refused = std::move(on_refused);
    entry->dispatch = [handler = std::move(handler)](const void* data, size_t size,
                                                      const std::string& ch, WireCheck* check) {
      Msg msg;
      *check = decodeChecked(data, size, &msg);
      if (check->error != WireError::kNone) return false;
      handler(msg, ch);
      return true;
    };
    lcm_->subscribeFunction(channel, &MessageGuard::onMessage, entry.get());
    entries_.push_back(std::move(entry));
  }

  /// Records arrivals on the channels `watch` watches (nullptr: none). `watch` must outlive
  /// the guard's handling of messages and addTo() calls.
  void setInputWatch(InputWatch* watch) { input_watch_ = watch; }
  /// Subscribes `heartbeat_channel` (heartbeat_t) and tells `watch` of every heartbeat, so a
  /// second instance of this process on the bus is noticed (PeerWatch). `watch` must outlive
  /// the guard's handling of messages and addTo() calls. Call once, before handling.
  void setPeerWatch(PeerWatch* watch, const std::string& heartbeat_channel);

  MessageGuardCounts counts() const;
  /// Adds "messages_refused_<kind>" for every WireError kind and "handler_errors", then, with
  /// an InputWatch, its counters and state (InputWatch::addTo), and with a PeerWatch its
  /// (PeerWatch::addTo).
  void addTo(HeartbeatBuilder* heartbeat) const;

 private:
  struct Entry {
    MessageGuard* guard = nullptr;
    RefusedCallback on_refused;
    // Checks, decodes and handles one message; false (with *check set) when refused.
    std::function<bool(const void*, size_t, const std::string&, WireCheck*)> dispatch;
  };
  static void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Entry* entry);
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Entry* entry);

  lcm::LCM* lcm_;
  LogSink log_;
  RateLimitedLog problem_log_;
  std::vector<std::unique_ptr<Entry>> entries_;
  InputWatch* input_watch_ = nullptr;
  PeerWatch* peer_watch_ = nullptr;
  std::atomic<uint64_t> accepted_{0}, handler_errors_{0};
  std::array<std::atomic<uint64_t>, static_cast<size_t>(WireError::kCount)> refused_{};
};

}  // namespace cblox
