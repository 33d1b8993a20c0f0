#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <utility>

#include <Eigen/Core>

#include "core/features/orb_descriptor.h"
#include "core/tracking/keyframe_order.h"

namespace cblox {

class Keyframe;
class ScalePyramid;

using LandmarkId = uint64_t;

/// A 3D point of the sparse map (ORB-SLAM2's MapPoint): position in G, the keyframe features
/// that observe it, a representative descriptor, a mean viewing direction and the distance
/// range over which ORB can detect it (scale invariance).
///
/// Thread-safety: `id` is immutable. Everything else is guarded by the SparseMap's mutex
/// (read under a shared lock, written under an exclusive lock), except the visible/found
/// counters, which are atomics the tracking thread bumps under a shared lock.
class Landmark : public std::enable_shared_from_this<Landmark> {
 public:
  Landmark(LandmarkId id, const Eigen::Vector3d& p_G, Keyframe* reference_keyframe);

  const LandmarkId id;

  const Eigen::Vector3d& position() const { return p_G_; }
  void setPosition(const Eigen::Vector3d& p_G) { p_G_ = p_G; }

  /// Observing keyframes and the index of the observing feature in each.
  const std::map<Keyframe*, uint32_t, KeyframeIdLess>& observations() const {
    return observations_;
  }
  /// Number of observations, a stereo observation counting 2 (as ORB-SLAM2's nObs).
  int numObservations() const { return num_obs_; }
  /// Adds (or keeps) keyframe's feature `index` as an observation; `stereo` when the feature
  /// has depth.
  void addObservation(Keyframe* keyframe, uint32_t index, bool stereo);
  /// Removes keyframe's observation. Returns true when the landmark is left with <= 2
  /// observations (the caller should then retire it, as ORB-SLAM2 does).
  bool eraseObservation(Keyframe* keyframe, bool stereo);
  /// Feature index in `keyframe`, or -1.
  int indexIn(const Keyframe* keyframe) const;

  Keyframe* referenceKeyframe() const { return reference_keyframe_; }
  void setReferenceKeyframe(Keyframe* keyframe) { reference_keyframe_ = keyframe; }

  /// Representative descriptor: the observation descriptor with the least median Hamming
  /// distance to the others (ORB-SLAM2's ComputeDistinctiveDescriptors).
  const OrbDescriptor& descriptor() const { return descriptor_; }
  void updateDescriptor();

  /// Mean unit viewing direction (from the observing cameras to the point) and the distance
  /// range [min, max] (metres) in which the point can be detected at some pyramid level,
  /// from the reference keyframe's observation (ORB-SLAM2's UpdateNormalAndDepth).
  void updateNormalAndDepth(const ScalePyramid& pyramid);
  const Eigen::Vector3d& normal() const { return normal_; }
  double minDistance() const { return 0.8 * min_distance_; }
  double maxDistance() const { return 1.2 * max_distance_; }
  /// Pyramid level at which a feature of this landmark is expected at `distance` metres.
  int predictScale(double distance, const ScalePyramid& pyramid) const;

  /// Restores what a snapshot recorded of the derived state (SparseMap::restore only):
  /// the representative descriptor, the viewing direction, the raw distance range and the
  /// visible / found counters.
  void restoreDerived(const OrbDescriptor& descriptor, const Eigen::Vector3d& normal,
                      double min_distance, double max_distance, int visible, int found);
  double rawMinDistance() const { return min_distance_; }
  double rawMaxDistance() const { return max_distance_; }

  /// Retired: culled, or merged into another landmark (replacement()).
  bool bad() const { return bad_; }
  void setBad() { bad_ = true; }
  const std::shared_ptr<Landmark>& replacement() const { return replaced_by_; }
  void setReplacement(std::shared_ptr<Landmark> other) { replaced_by_ = std::move(other); }

  /// Tracking statistics: frames that should have seen it / that matched it.
  void increaseVisible(int n = 1) { visible_.fetch_add(n, std::memory_order_relaxed); }
  void increaseFound(int n = 1) { found_.fetch_add(n, std::memory_order_relaxed); }
  int visible() const { return visible_.load(std::memory_order_relaxed); }
  int found() const { return found_.load(std::memory_order_relaxed); }
  /// found / visible (1 when never visible).
  double foundRatio() const;

  /// Keyframe id at whose creation the landmark was made (local mapping culls recent ones).
  KeyframeId first_keyframe_id = 0;
  /// Tracking bookkeeping: last frame that tracked it / tested it for the local map.
  uint64_t track_reference_frame = 0;
  uint64_t last_seen_frame = 0;
  /// Local BA / loop closing bookkeeping (keyframe id of the BA run that last touched it).
  KeyframeId ba_local_for_keyframe = -1;
  KeyframeId fuse_candidate_for_keyframe = -1;
  KeyframeId loop_point_for_keyframe = -1;
  KeyframeId corrected_by_keyframe = -1;

 private:
  Eigen::Vector3d p_G_;
  Eigen::Vector3d normal_ = Eigen::Vector3d::Zero();
  double min_distance_ = 0.0, max_distance_ = 0.0;
  std::map<Keyframe*, uint32_t, KeyframeIdLess> observations_;
  int num_obs_ = 0;
  Keyframe* reference_keyframe_;
  OrbDescriptor descriptor_;
  bool bad_ = false;
  std::shared_ptr<Landmark> replaced_by_;
  std::atomic<int> visible_{1}, found_{1};
};

}  // namespace cblox
