#pragma once

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <exception>

#include "daemon/config/yaml_config.h"

namespace cblox {

/// Set by SIGINT / SIGTERM once installStopHandlers() ran: the process's main loop polls it
/// to finish the work in hand and exit 0. Lock-free, so safe to set from a signal handler.
inline std::atomic<bool> g_stop_requested{false};

/// Makes SIGINT and SIGTERM set g_stop_requested (instead of killing the process).
inline void installStopHandlers() {
  static_assert(std::atomic<bool>::is_always_lock_free);
  const auto handler = [](int) { g_stop_requested = true; };
  std::signal(SIGINT, handler);
  std::signal(SIGTERM, handler);
}

/// Wall-clock time in microseconds since the Unix epoch (LCM message time stamps).
inline int64_t wallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// Runs a process's body and turns what escapes it into the exit statuses every cblox
/// process documents: ConfigError (usage or configuration) -> 2, any other exception
/// (runtime error) -> 1, each with one line on stderr naming the process. `body` returns
/// the exit status. Call from main(); not for library code.
template <typename Body>
int runProcess(const char* name, Body&& body) {
  try {
    return body();
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "%s: configuration error: %s\n", name, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace cblox
