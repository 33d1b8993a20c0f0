#pragma once

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include "core/common/utime_ns.h"  // wallUtime()
#include "daemon/common/systemd_notify.h"
#include "daemon/common/yaml_config.h"

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

/// A task of serveUntilStopped: run every period_s seconds, the first time first_after_s
/// seconds after the loop starts.
struct PeriodicTask {
  double period_s = 1.0;
  double first_after_s = 0.0;
  std::function<void()> run;
};

/// The daemons' main loop: handles `lcm`'s messages (waiting at most 50 ms at a time) until
/// g_stop_requested, and runs each task when it is due. With a `notifier` (systemd), it sends
/// READY=1 when it starts serving, WATCHDOG=1 from this loop while it turns (so a task or
/// handler that hangs stops the pings) and STOPPING=1 when it leaves. Returns 0 after a stop
/// request, 1 when receiving fails (one line on stderr naming the process). Lcm: lcm::LCM or
/// anything with its handleTimeout(int ms). Call from the process's main thread.
template <typename Lcm>
int serveUntilStopped(Lcm& lcm, const char* name, const std::vector<PeriodicTask>& tasks,
                      SystemdNotifier* notifier = nullptr) {
  using Clock = std::chrono::steady_clock;
  const auto after = [](double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  };
  const Clock::time_point start = Clock::now();
  std::vector<Clock::time_point> next;
  for (const PeriodicTask& task : tasks) next.push_back(start + after(task.first_after_s));
  if (notifier) notifier->ready(std::string(name) + ": serving");
  int exit_code = 0;
  while (!g_stop_requested) {
    if (lcm.handleTimeout(50) < 0 && !g_stop_requested) {
      std::fprintf(stderr, "%s: LCM receive failed\n", name);
      exit_code = 1;
      break;
    }
    const Clock::time_point now = Clock::now();
    for (size_t i = 0; i < tasks.size(); ++i) {
      if (now < next[i]) continue;
      tasks[i].run();
      next[i] = now + after(tasks[i].period_s);
    }
    if (notifier) notifier->pingWatchdogIfDue();
  }
  if (notifier) notifier->stopping();
  return exit_code;
}

}  // namespace cblox
