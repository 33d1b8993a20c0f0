#include "core/common/thread_priority.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace cblox {

std::string lowerThreadPriority(int niceness, bool sched_idle) {
  std::string problems;
  const pid_t tid = static_cast<pid_t>(::syscall(SYS_gettid));
  if (::setpriority(PRIO_PROCESS, static_cast<id_t>(tid), niceness) != 0) {
    problems = "cannot set niceness " + std::to_string(niceness) + ": " + std::strerror(errno);
  }
  if (sched_idle) {
    sched_param param{};
    param.sched_priority = 0;
    if (const int e = pthread_setschedparam(pthread_self(), SCHED_IDLE, &param); e != 0) {
      problems += (problems.empty() ? "" : "; ") + std::string("cannot switch to SCHED_IDLE: ") +
                  std::strerror(e);
    }
  }
  return problems;
}

}  // namespace cblox
