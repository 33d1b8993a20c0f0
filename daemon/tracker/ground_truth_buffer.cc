#include "daemon/tracker/ground_truth_buffer.h"

namespace cblox {

void GroundTruthBuffer::add(int64_t frame_id, int64_t utime, const Transformationd& T_G_C) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // Time going back: the source restarted; the old stream's poses could match new frames.
    if (!entries_.empty() && utime < entries_.back().utime) entries_.clear();
    entries_.push_back(Entry{frame_id, utime, T_G_C});
    while (entries_.size() > capacity_) entries_.pop_front();
  }
  added_.notify_all();
}

std::optional<Transformationd> GroundTruthBuffer::waitFor(int64_t frame_id, int64_t utime,
                                                          std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  std::optional<Transformationd> found;
  added_.wait_for(lock, timeout, [&] {
    found = find(frame_id, utime);
    return found.has_value() || interrupted_;
  });
  return found;
}

void GroundTruthBuffer::interrupt() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    interrupted_ = true;
  }
  added_.notify_all();
}

std::optional<Transformationd> GroundTruthBuffer::find(int64_t frame_id, int64_t utime) const {
  for (auto it = entries_.rbegin(); it != entries_.rend(); ++it) {
    if (it->frame_id >= 0 ? it->frame_id == frame_id : it->utime == utime) return it->T_G_C;
  }
  return std::nullopt;
}

}  // namespace cblox
