#pragma once

#include <ctime>

namespace cblox {

/// CPU seconds the calling thread has used so far (Linux CLOCK_THREAD_CPUTIME_ID: user +
/// system time of this thread only, not the time it waited for a lock or the processor).
/// The difference of two readings on the same thread is what a piece of work cost that
/// thread; 0 if the clock cannot be read.
inline double threadCpuSeconds() {
  timespec t{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t) != 0) return 0.0;
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace cblox
