#pragma once

#include <string>

#include <sys/prctl.h>

namespace cblox {

/// Names the calling thread for the operating system (Linux PR_SET_NAME: what `top -H`,
/// `ps -L`, htop and /proc/PID/task/TID/comm show), truncated to the kernel's 15 bytes. cblox
/// names each of its threads `cblox-<job>` so that an operator sees which one takes the CPU.
/// Best effort: a failure leaves the inherited name.
inline void nameThisThread(const std::string& name) {
  const std::string shown = name.substr(0, 15);
  prctl(PR_SET_NAME, shown.c_str(), 0, 0, 0);
}

}  // namespace cblox
