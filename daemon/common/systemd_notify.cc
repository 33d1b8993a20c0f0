#include "daemon/common/systemd_notify.h"

#include <systemd/sd-daemon.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>

namespace cblox {

SystemdNotifier::SystemdNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  enabled_ = socket != nullptr && socket[0] != '\0';
  uint64_t usec = 0;
  if (enabled_ && sd_watchdog_enabled(0, &usec) > 0) {
    watchdog_interval_ = std::chrono::microseconds(usec);
  }
}

void SystemdNotifier::send(const std::string& state) {
  if (enabled_) sd_notify(0, state.c_str());
}

void SystemdNotifier::ready(const std::string& status_line) {
  std::string line = status_line;
  std::replace(line.begin(), line.end(), '\n', ' ');
  send("READY=1\nSTATUS=" + line);
  last_ping_ = Clock::now();
}

void SystemdNotifier::status(const std::string& status_line) {
  std::string line = status_line;
  std::replace(line.begin(), line.end(), '\n', ' ');
  send("STATUS=" + line);
}

void SystemdNotifier::stopping() { send("STOPPING=1"); }

void SystemdNotifier::pingWatchdogIfDue(Clock::time_point now) {
  if (!watchdogEnabled() || now - last_ping_ < watchdog_interval_ / 2) return;
  send("WATCHDOG=1");
  last_ping_ = now;
}

}  // namespace cblox
