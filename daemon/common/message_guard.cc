#include "daemon/common/message_guard.h"

#include <cstdio>

#include <cblox/heartbeat_t.hpp>

namespace cblox {

namespace {
constexpr size_t kNumWireErrors = static_cast<size_t>(WireError::kCount);
constexpr size_t kHandlerErrorKind = kNumWireErrors;  // RateLimitedLog kind of handler errors
}  // namespace

uint64_t MessageGuardCounts::refusedTotal() const {
  uint64_t total = 0;
  for (const uint64_t n : refused) total += n;
  return total;
}

MessageGuard::MessageGuard(lcm::LCM* lcm, LogSink log,
                           std::chrono::steady_clock::duration log_interval)
    : lcm_(lcm),
      log_(log ? std::move(log)
               : LogSink([](const std::string& line) {
                   std::fprintf(stderr, "%s\n", line.c_str());
                 })),
      problem_log_(kNumWireErrors + 1, log_interval, log_) {}

void MessageGuard::onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                             Entry* entry) {
  entry->guard->handle(rbuf, channel, entry);
}

void MessageGuard::handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                          Entry* entry) {
  // kDecodeFailed until dispatch() stores the check's result: an exception before that is not
  // an arrival.
  WireCheck check{WireError::kDecodeFailed, {}};
  const size_t size = rbuf->data_size;
  try {
    if (entry->dispatch(rbuf->data, size, channel, &check)) {
      ++accepted_;
      if (input_watch_) input_watch_->arrived(channel);
      return;
    }
  } catch (const std::exception& e) {
    ++handler_errors_;
    if (input_watch_ && check.ok()) input_watch_->arrived(channel);
    problem_log_.report(kHandlerErrorKind,
                        channel + ": message handler failed, message dropped: " + e.what());
    return;
  } catch (...) {
    ++handler_errors_;
    if (input_watch_ && check.ok()) input_watch_->arrived(channel);
    problem_log_.report(kHandlerErrorKind,
                        channel + ": message handler failed (unknown exception), message dropped");
    return;
  }
  const size_t kind = static_cast<size_t>(check.error);
  if (kind < kNumWireErrors) ++refused_[kind];
  const std::string description = channel + ": message of " + std::to_string(size) +
                                  " bytes refused (" + wireErrorName(check.error) +
                                  "): " + check.detail;
  if (entry->on_refused) {
    try {
      entry->on_refused(description);
      return;
    } catch (...) {
      // Fall through to the guard's own log line.
    }
  }
  problem_log_.report(kind, description);
}

MessageGuardCounts MessageGuard::counts() const {
  MessageGuardCounts c;
  c.accepted = accepted_.load();
  c.handler_errors = handler_errors_.load();
  for (size_t i = 0; i < kNumWireErrors; ++i) c.refused[i] = refused_[i].load();
  return c;
}

void MessageGuard::addTo(HeartbeatBuilder* heartbeat) const {
  const MessageGuardCounts c = counts();
  for (size_t i = 0; i < kNumWireErrors; ++i) {
    if (static_cast<WireError>(i) == WireError::kNone) continue;
    heartbeat->add(std::string("messages_refused_") + wireErrorName(static_cast<WireError>(i)),
                   c.refused[i]);
  }
  heartbeat->add("handler_errors", c.handler_errors);
  if (input_watch_) input_watch_->addTo(heartbeat);
  if (peer_watch_) peer_watch_->addTo(heartbeat);
}

void MessageGuard::setPeerWatch(PeerWatch* watch, const std::string& heartbeat_channel) {
  peer_watch_ = watch;
  subscribe<heartbeat_t>(heartbeat_channel, [watch](const heartbeat_t& msg, const std::string&) {
    watch->onHeartbeat(msg.process, msg.pid);
  });
}

}  // namespace cblox
