#include "drivers/camera/stereo_pairer.h"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace cblox {
namespace {

int64_t absDiff(int64_t a, int64_t b) { return a > b ? a - b : b - a; }

}  // namespace

std::string StereoPairerOptions::validate() const {
  if (tolerance_ns <= 0) return "tolerance_ns must be > 0, got " + std::to_string(tolerance_ns);
  if (max_wait_ns < tolerance_ns) {
    return "max_wait_ns must be >= tolerance_ns (" + std::to_string(tolerance_ns) + "), got " +
           std::to_string(max_wait_ns);
  }
  if (max_queue < 1) return "max_queue must be >= 1";
  return {};
}

std::string_view stereoDropReasonName(StereoDropReason reason) {
  switch (reason) {
    case StereoDropReason::kUnpaired:
      return "unpaired";
    case StereoDropReason::kExpired:
      return "expired";
    case StereoDropReason::kOverflow:
      return "overflow";
    case StereoDropReason::kOutOfOrder:
      return "out_of_order";
    case StereoDropReason::kFlushed:
      return "flushed";
  }
  return "unknown";
}

StereoPairer::StereoPairer(const StereoPairerOptions& options) : options_(options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("StereoPairer: " + problem);
  }
}

size_t StereoPairer::waiting(StereoSide side) const {
  return (side == StereoSide::kLeft ? left_ : right_).queue.size();
}

void StereoPairer::consume(StereoSide side, int64_t timestamp_ns) {
  Stream& s = stream(side);
  if (s.last_consumed_ns) s.interval_ns = timestamp_ns - *s.last_consumed_ns;
  s.last_consumed_ns = timestamp_ns;
}

bool StereoPairer::isDrift(StereoSide side, int64_t timestamp_ns) const {
  const Stream& other = side == StereoSide::kLeft ? right_ : left_;
  if (!other.interval_ns) return false;
  std::optional<int64_t> nearest;
  if (!other.queue.empty()) nearest = absDiff(other.queue.front().timestamp_ns, timestamp_ns);
  if (other.last_consumed_ns) {
    const int64_t d = absDiff(*other.last_consumed_ns, timestamp_ns);
    nearest = nearest ? std::min(*nearest, d) : d;
  }
  return nearest && *nearest > options_.tolerance_ns && 2 * *nearest < *other.interval_ns;
}

void StereoPairer::drop(StereoSide side, StereoDropReason reason, std::vector<StereoDrop>* drops) {
  Stream& s = stream(side);
  const Entry entry = s.queue.front();
  if (reason == StereoDropReason::kUnpaired && isDrift(side, entry.timestamp_ns)) ++stats_.drift;
  s.queue.pop_front();
  consume(side, entry.timestamp_ns);
  if (reason == StereoDropReason::kOverflow) ++stats_.overflow;
  ++(side == StereoSide::kLeft ? stats_.left_unpaired : stats_.right_unpaired);
  drops->push_back(StereoDrop{side, entry.id, entry.timestamp_ns, reason});
}

void StereoPairer::push(StereoSide side, int64_t timestamp_ns, uint64_t id,
                        std::vector<StereoPair>* pairs, std::vector<StereoDrop>* drops) {
  Stream& s = stream(side);
  const bool stale = s.last_consumed_ns && timestamp_ns <= *s.last_consumed_ns;
  const bool duplicate = std::any_of(s.queue.begin(), s.queue.end(), [&](const Entry& e) {
    return e.timestamp_ns == timestamp_ns;
  });
  if (stale || duplicate) {
    ++stats_.out_of_order;
    drops->push_back(StereoDrop{side, id, timestamp_ns, StereoDropReason::kOutOfOrder});
    return;
  }
  const auto at = std::upper_bound(s.queue.begin(), s.queue.end(), timestamp_ns,
                                   [](int64_t t, const Entry& e) { return t < e.timestamp_ns; });
  s.queue.insert(at, Entry{timestamp_ns, id});
  newest_ns_ = newest_ns_ ? std::max(*newest_ns_, timestamp_ns) : timestamp_ns;
  match(pairs, drops);
}

void StereoPairer::match(std::vector<StereoPair>* pairs, std::vector<StereoDrop>* drops) {
  const int64_t tolerance = options_.tolerance_ns;
  while (!left_.queue.empty() && !right_.queue.empty()) {
    const Entry l = left_.queue.front();
    const Entry r = right_.queue.front();
    const int64_t dt = r.timestamp_ns - l.timestamp_ns;
    if (dt > tolerance) {
      drop(StereoSide::kLeft, StereoDropReason::kUnpaired, drops);
      continue;
    }
    if (dt < -tolerance) {
      drop(StereoSide::kRight, StereoDropReason::kUnpaired, drops);
      continue;
    }
    const int64_t distance = std::abs(dt);
    if (right_.queue.size() > 1 &&
        absDiff(right_.queue[1].timestamp_ns, l.timestamp_ns) < distance) {
      drop(StereoSide::kRight, StereoDropReason::kUnpaired, drops);
      continue;
    }
    if (left_.queue.size() > 1 && absDiff(left_.queue[1].timestamp_ns, r.timestamp_ns) < distance) {
      drop(StereoSide::kLeft, StereoDropReason::kUnpaired, drops);
      continue;
    }
    left_.queue.pop_front();
    right_.queue.pop_front();
    consume(StereoSide::kLeft, l.timestamp_ns);
    consume(StereoSide::kRight, r.timestamp_ns);
    ++stats_.pairs;
    stats_.last_dt_ns = dt;
    stats_.max_abs_dt_ns = std::max(stats_.max_abs_dt_ns, distance);
    pairs->push_back(StereoPair{l.id, r.id, l.timestamp_ns, r.timestamp_ns});
  }
  // At most one side still has frames: they wait, within bounds.
  for (StereoSide side : {StereoSide::kLeft, StereoSide::kRight}) {
    Stream& s = stream(side);
    while (!s.queue.empty() && s.queue.front().timestamp_ns < *newest_ns_ - options_.max_wait_ns) {
      drop(side, StereoDropReason::kExpired, drops);
    }
    while (s.queue.size() > options_.max_queue) drop(side, StereoDropReason::kOverflow, drops);
  }
}

void StereoPairer::clear(std::vector<StereoDrop>* drops) {
  for (StereoSide side : {StereoSide::kLeft, StereoSide::kRight}) {
    Stream& s = stream(side);
    for (const Entry& e : s.queue) {
      drops->push_back(StereoDrop{side, e.id, e.timestamp_ns, StereoDropReason::kFlushed});
    }
    s = Stream{};
  }
  newest_ns_.reset();
}

}  // namespace cblox
