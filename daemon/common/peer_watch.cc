#include "daemon/common/peer_watch.h"

#include <cstdio>
#include <stdexcept>
#include <utility>

namespace cblox {

PeerWatch::PeerWatch(std::string process, int32_t own_pid, double forget_after_s, LogSink log,
                     NowFn now)
    : process_(std::move(process)),
      own_pid_(own_pid),
      forget_after_s_(forget_after_s),
      log_(log ? std::move(log)
               : LogSink([](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); })),
      now_(now ? std::move(now) : NowFn([] { return Clock::now(); })) {
  if (!(forget_after_s > 0.0)) throw std::invalid_argument("PeerWatch: forget_after_s must be > 0");
}

void PeerWatch::onHeartbeat(const std::string& process, int32_t pid) {
  if (process != process_ || pid == own_pid_) return;
  bool appeared = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    appeared = last_heard_.find(pid) == last_heard_.end();
    last_heard_[pid] = now_();
    seen_.insert(pid);
  }
  if (appeared) {
    log_(process_ + ": another " + process_ + " (pid " + std::to_string(pid) +
         ") is on this bus: both take the same inputs and publish on the same channels; stop "
         "one of them (a second launch, or the systemd unit running as well)");
  }
}

std::vector<int32_t> PeerWatch::peers() {
  std::vector<int32_t> present, gone;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const Clock::time_point now = now_();
    for (auto it = last_heard_.begin(); it != last_heard_.end();) {
      if (std::chrono::duration<double>(now - it->second).count() >= forget_after_s_) {
        gone.push_back(it->first);
        it = last_heard_.erase(it);
      } else {
        present.push_back(it->first);
        ++it;
      }
    }
  }
  for (const int32_t pid : gone) {
    log_(process_ + ": the other " + process_ + " (pid " + std::to_string(pid) + ") is gone");
  }
  return present;
}

uint64_t PeerWatch::peersSeen() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return seen_.size();
}

void PeerWatch::addTo(HeartbeatBuilder* heartbeat) {
  const std::vector<int32_t> present = peers();
  heartbeat->add("other_instances", static_cast<uint64_t>(present.size()));
  heartbeat->add("other_instances_seen", peersSeen());
  if (present.empty()) return;
  std::string pids;
  for (const int32_t pid : present) pids += (pids.empty() ? "" : ", ") + std::to_string(pid);
  const std::string prefix = "another " + process_ + " on this bus (pid " + pids + ")";
  const std::string& state = heartbeat->state();
  heartbeat->setState(state.empty() ? prefix : prefix + "; " + state);
}

}  // namespace cblox
