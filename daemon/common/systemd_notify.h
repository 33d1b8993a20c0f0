#pragma once

// systemd's notify protocol for Type=notify units (sd_notify(3)): READY=1 once the process
// serves, STATUS= a one-line summary, WATCHDOG=1 from the main loop while it turns, and
// STOPPING=1 on the way out. Outside systemd (no NOTIFY_SOCKET) every call does nothing.

#include <chrono>
#include <string>

namespace cblox {

/// Thread-safety: not thread-safe; the process's main loop owns it.
class SystemdNotifier {
 public:
  using Clock = std::chrono::steady_clock;

  /// Reads NOTIFY_SOCKET, and WATCHDOG_USEC / WATCHDOG_PID through sd_watchdog_enabled().
  SystemdNotifier();

  /// True when NOTIFY_SOCKET is set (started by systemd, or by a test that owns the socket).
  bool enabled() const { return enabled_; }
  /// True when the unit has WatchdogSec= (WATCHDOG_USEC set for this pid).
  bool watchdogEnabled() const { return watchdog_interval_.count() > 0; }
  std::chrono::microseconds watchdogInterval() const { return watchdog_interval_; }

  /// READY=1 with a STATUS= line.
  void ready(const std::string& status);
  /// STATUS= line (newlines are replaced by spaces).
  void status(const std::string& status);
  /// STOPPING=1.
  void stopping();
  /// WATCHDOG=1 when half the watchdog interval has passed since the last ping (systemd's
  /// advice); call it from the main loop on every turn, never from a helper thread, so that
  /// a hung main loop stops the pings and systemd restarts the unit.
  void pingWatchdogIfDue(Clock::time_point now = Clock::now());

 private:
  void send(const std::string& state);

  bool enabled_ = false;
  std::chrono::microseconds watchdog_interval_{0};
  Clock::time_point last_ping_{};
};

}  // namespace cblox
