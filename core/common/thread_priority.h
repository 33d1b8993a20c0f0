#pragma once

// Lowers the calling thread's CPU priority: the low-priority workers of the daemons (the
// mapper's fusion/export worker, the tracker's checkpoint writer) run on what the tracking
// and integration threads leave.

#include <string>

namespace cblox {

/// Sets the calling thread's niceness (setpriority on its tid; 0..19) and, when `sched_idle`,
/// switches it to SCHED_IDLE. Returns an empty string, or what failed (the thread keeps
/// running at the priority it could get). Thread-safe (affects the caller only).
std::string lowerThreadPriority(int niceness, bool sched_idle);

}  // namespace cblox
