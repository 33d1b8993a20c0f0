#pragma once

// The camera's path as the map knows it: each integrated frame's position in the frame M of
// the subvolume it went into, so that drawn in G through the subvolumes' current poses the
// path moves with them when a loop closure corrects them (as the map does).

#include <cstddef>
#include <mutex>
#include <vector>

#include <Eigen/Core>

#include "core/submap/submap.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// A bounded log of camera positions per subvolume. A position closer than min_step_m to
/// the previous one of the same subvolume is not kept; when the log holds `capacity`
/// positions, every second one is dropped (the whole path stays, coarser) and min_step_m
/// doubles. Thread-safety: every member function is thread-safe (one mutex).
class TrajectoryLog {
 public:
  /// capacity >= 2, min_step_m >= 0 (else std::invalid_argument).
  explicit TrajectoryLog(size_t capacity = 20000, double min_step_m = 0.05);

  /// Records the camera at p_M in subvolume `id`.
  void add(SubmapId id, const Eigen::Vector3d& p_M);
  /// The positions in G, in the order recorded, through `poses` (SubmapCollection::
  /// poseSnapshot()); positions of subvolumes not in `poses` (fused away, removed) are left
  /// out.
  std::vector<Eigen::Vector3d> positionsG(const std::vector<SubmapPose>& poses) const;
  size_t size() const;

 private:
  struct Entry {
    SubmapId id;
    Eigen::Vector3d p_M;
  };
  const size_t capacity_;
  mutable std::mutex mutex_;
  double min_step_m_;
  std::vector<Entry> entries_;
};

}  // namespace cblox
