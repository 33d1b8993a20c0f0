#pragma once

// The in-process LCM bus (memq://) of the node fuzz targets: the input is published on a
// channel and delivered to the node's subscriptions, so that it takes the live path of a
// daemon (message guard: wire check, decode, handler), and whatever the node publishes in
// answer is delivered too (its own subscriptions see it, as on the real bus).

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <lcm/lcm-cpp.hpp>

namespace cblox::fuzz {

class MemqBus {
 public:
  MemqBus() : lcm_("memq://") {
    if (!lcm_.good()) throw std::runtime_error("cannot open the in-process LCM (memq://)");
  }
  lcm::LCM* lcm() { return &lcm_; }

  /// Publishes the bytes on `channel` and delivers everything queued. Not thread-safe.
  void deliver(const std::string& channel, const uint8_t* data, size_t size) {
    lcm_.publish(channel, data, static_cast<unsigned int>(size));
    drain();
  }
  /// Delivers everything queued (messages the handlers published meanwhile too).
  void drain() {
    while (lcm_.handleTimeout(0) > 0) {
    }
  }

 private:
  lcm::LCM lcm_;
};

}  // namespace cblox::fuzz
