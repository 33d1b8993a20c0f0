#include "core/mapping/pose_buffer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cblox {

std::string PoseBuffer::Config::validate() const {
  if (!(max_gap_s > 0.0) || !std::isfinite(max_gap_s)) {
    return "max_gap_s must be > 0, got " + std::to_string(max_gap_s);
  }
  if (capacity < 2) return "capacity must be >= 2, got " + std::to_string(capacity);
  return {};
}

PoseBuffer::PoseBuffer(const Config& config) : config_(config) {
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::invalid_argument("PoseBuffer::Config: " + problem);
  }
}

PoseBuffer::AddResult PoseBuffer::add(const TimedPose& pose) {
  const Eigen::Quaterniond& q = pose.T_G_C.rotation();
  if (!pose.T_G_C.translation().allFinite() || !q.coeffs().allFinite() ||
      std::abs(q.norm() - 1.0) > 1e-3) {
    return AddResult::kInvalid;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!poses_.empty()) {
    if (pose.utime == poses_.back().utime) return AddResult::kDuplicate;
    if (pose.utime < poses_.back().utime) return AddResult::kOutOfOrder;
  }
  poses_.push_back(pose);
  while (poses_.size() > config_.capacity) poses_.pop_front();
  return AddResult::kAdded;
}

PoseBuffer::Lookup PoseBuffer::lookup(int64_t utime, Transformationd* T_G_C, bool* jump,
                                      int64_t* reference_keyframe) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return lookupLocked(utime, T_G_C, jump, reference_keyframe);
}

PoseBuffer::Lookup PoseBuffer::lookupLocked(int64_t utime, Transformationd* T_G_C, bool* jump,
                                            int64_t* reference_keyframe) const {
  if (poses_.empty() || utime > poses_.back().utime) return Lookup::kNotYet;
  if (utime < poses_.front().utime) return Lookup::kTooOld;
  const auto after = std::lower_bound(
      poses_.begin(), poses_.end(), utime,
      [](const TimedPose& p, int64_t t) { return p.utime < t; });  // first with utime >= t
  if (after->utime == utime) {
    if (!after->tracking_ok) return Lookup::kLost;
    *T_G_C = after->T_G_C;
    *jump = after->jump;
    if (reference_keyframe != nullptr) *reference_keyframe = after->reference_keyframe;
    return Lookup::kFound;
  }
  const auto before = after - 1;  // utime > front: after is not the first
  if (!before->tracking_ok || !after->tracking_ok) return Lookup::kLost;
  if (after->jump || after->epoch != before->epoch) return Lookup::kAcrossJump;
  const double gap_s = static_cast<double>(after->utime - before->utime) * 1e-6;
  if (gap_s > config_.max_gap_s) return Lookup::kGap;
  const double alpha = static_cast<double>(utime - before->utime) /
                       static_cast<double>(after->utime - before->utime);
  *T_G_C = Transformationd::interpolate(before->T_G_C, after->T_G_C, alpha);
  *jump = false;
  if (reference_keyframe != nullptr) {
    *reference_keyframe = alpha < 0.5 ? before->reference_keyframe : after->reference_keyframe;
  }
  return Lookup::kFound;
}

size_t PoseBuffer::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return poses_.size();
}

int64_t PoseBuffer::newestUtime() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return poses_.empty() ? std::numeric_limits<int64_t>::min() : poses_.back().utime;
}

std::optional<TimedPose> PoseBuffer::newestTracked() const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = poses_.rbegin(); it != poses_.rend(); ++it) {
    if (it->tracking_ok) return *it;
  }
  return std::nullopt;
}

void PoseBuffer::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  poses_.clear();
}

const char* PoseBuffer::name(Lookup result) {
  switch (result) {
    case Lookup::kFound:
      return "found";
    case Lookup::kNotYet:
      return "pose not yet received";
    case Lookup::kTooOld:
      return "older than every pose kept";
    case Lookup::kGap:
      return "gap between poses too long";
    case Lookup::kAcrossJump:
      return "across a tracking jump";
    case Lookup::kLost:
      return "tracking lost";
  }
  return "?";
}

}  // namespace cblox
