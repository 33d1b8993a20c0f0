#include "core/mapping/trajectory_log.h"

#include <stdexcept>
#include <unordered_map>

namespace cblox {

TrajectoryLog::TrajectoryLog(size_t capacity, double min_step_m)
    : capacity_(capacity), min_step_m_(min_step_m) {
  if (capacity < 2) throw std::invalid_argument("TrajectoryLog: capacity must be >= 2");
  if (!(min_step_m >= 0.0)) throw std::invalid_argument("TrajectoryLog: min_step_m must be >= 0");
}

void TrajectoryLog::add(SubmapId id, const Eigen::Vector3d& p_M) {
  if (!p_M.allFinite()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!entries_.empty() && entries_.back().id == id &&
      (entries_.back().p_M - p_M).norm() < min_step_m_) {
    return;
  }
  if (entries_.size() >= capacity_) {
    size_t kept = 0;
    for (size_t i = 0; i < entries_.size(); i += 2) entries_[kept++] = entries_[i];
    entries_.resize(kept);
    min_step_m_ = min_step_m_ > 0.0 ? 2.0 * min_step_m_ : 0.0;
  }
  entries_.push_back(Entry{id, p_M});
}

std::vector<Eigen::Vector3d> TrajectoryLog::positionsG(const std::vector<SubmapPose>& poses) const {
  std::unordered_map<SubmapId, const Transformationd*> by_id;
  for (const SubmapPose& pose : poses) by_id[pose.id] = &pose.T_G_M;
  std::vector<Eigen::Vector3d> out;
  std::lock_guard<std::mutex> lock(mutex_);
  out.reserve(entries_.size());
  for (const Entry& e : entries_) {
    const auto it = by_id.find(e.id);
    if (it != by_id.end()) out.push_back(*it->second * e.p_M);
  }
  return out;
}

size_t TrajectoryLog::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return entries_.size();
}

}  // namespace cblox
