#include "core/tracking/local_mapper.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/common/thread_cpu_clock.h"
#include "core/tracking/feature_measurement.h"
#include "core/tracking/landmark_fusion.h"

namespace cblox {

std::string LocalMapperConfig::validate() const {
  std::ostringstream error;
  if (!(min_found_ratio >= 0.0 && min_found_ratio <= 1.0)) {
    error << "min_found_ratio must be in [0, 1], got " << min_found_ratio;
  } else if (min_observations < 1) {
    error << "min_observations must be >= 1, got " << min_observations;
  } else if (fuse_neighbours < 0 || fuse_second_neighbours < 0) {
    error << "fuse_neighbours and fuse_second_neighbours must be >= 0";
  } else if (!(fuse_radius > 0.0f)) {
    error << "fuse_radius must be > 0, got " << fuse_radius;
  } else if (!(redundant_ratio > 0.0 && redundant_ratio <= 1.0)) {
    error << "redundant_ratio must be in (0, 1], got " << redundant_ratio;
  } else if (local_ba_max_keyframes < 0) {
    error << "local_ba_max_keyframes must be >= 0 (0 = all covisible), got "
          << local_ba_max_keyframes;
  } else if (std::string e = cblox::validate(bundle_adjustment); !e.empty()) {
    error << "bundle_adjustment: " << e;
  } else if (std::string t = triangulation.validate(); !t.empty()) {
    error << "triangulation: " << t;
  } else if (std::string d = disparity_correction.validate(); !d.empty()) {
    error << "disparity_correction: " << d;
  }
  return error.str();
}

namespace {

const LocalMapperConfig& validConfig(const LocalMapperConfig& config) {
  if (std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("LocalMapper: " + e);
  }
  return config;
}

}  // namespace

LocalMapper::LocalMapper(SparseMap* map, const TrackingCamera& camera, const ScalePyramid& pyramid,
                         const LocalMapperConfig& config)
    : map_(map),
      camera_(camera),
      pyramid_(pyramid),
      config_(config),
      disparity_correction_(validConfig(config).disparity_correction) {
  if (map == nullptr) throw std::invalid_argument("LocalMapper: map is null");
  if (std::string e = camera.validate(); !e.empty()) {
    throw std::invalid_argument("LocalMapper: camera: " + e);
  }
}

bool LocalMapper::acceptsKeyframes() const { return queue_.idle(); }

size_t LocalMapper::queuedKeyframes() const { return queue_.size(); }

void LocalMapper::insertKeyframe(Keyframe* keyframe) {
  // A new keyframe is more useful than finishing the current BA. Raised before the push:
  // raised after it, it could land once the worker has taken this very keyframe and reset
  // the flag for its BA, and abort that BA for nothing (a race that made runs differ).
  abort_ba_ = true;
  queue_.push(keyframe);
}

void LocalMapper::stop() {
  queue_.stop();
  abort_ba_ = true;
}

void LocalMapper::waitUntilIdle() { queue_.waitUntilIdle(); }

void LocalMapper::run() {
  while (queue_.waitForWork()) processOne();
}

LocalMapperStats LocalMapper::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

bool LocalMapper::processOne() {
  Keyframe* keyframe = queue_.tryPop();
  if (keyframe == nullptr) return false;
  LocalMapperStats::StepSeconds cpu;
  double clock = threadCpuSeconds();
  const auto lap = [&clock](double* step) {
    const double now = threadCpuSeconds();
    *step += now - clock;
    clock = now;
  };
  processNewKeyframe(keyframe);
  lap(&cpu.refresh);
  cullRecentLandmarks(keyframe);
  lap(&cpu.cull_landmarks);
  if (config_.create_new_landmarks) triangulateNewLandmarks(keyframe);
  lap(&cpu.triangulate);
  if (!queue_.moreWorkOrStopping()) fuseWithNeighbours(keyframe);
  lap(&cpu.fuse);
  abort_ba_ = false;
  if (!queue_.moreWorkOrStopping()) {
    localBundleAdjustment(keyframe);
    lap(&cpu.bundle_adjustment);
    if (config_.cull_keyframes) cullKeyframes(keyframe);
    lap(&cpu.cull_keyframes);
  }
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.keyframes_processed;
    stats_.cpu_s += cpu;
  }
  if (on_keyframe_) on_keyframe_(keyframe);
  queue_.done();
  return true;
}

void LocalMapper::processNewKeyframe(Keyframe* keyframe) {
  std::unique_lock<std::shared_mutex> lock(map_->mutex());
  for (Landmark* l : keyframe->landmarks()) {
    if (l == nullptr || l->bad()) continue;
    if (l->first_keyframe_id == keyframe->id && l->observations().size() == 1) {
      recent_landmarks_.push_back(l->shared_from_this());  // made by the tracker just now
    } else {
      l->updateNormalAndDepth(pyramid_);
      l->updateDescriptor();
    }
  }
  keyframe->updateConnections();
}

void LocalMapper::cullRecentLandmarks(Keyframe* keyframe) {
  std::unique_lock<std::shared_mutex> lock(map_->mutex());
  uint64_t culled = 0;
  for (auto it = recent_landmarks_.begin(); it != recent_landmarks_.end();) {
    Landmark* l = it->get();
    const KeyframeId age = keyframe->id - l->first_keyframe_id;
    if (l->bad()) {
      it = recent_landmarks_.erase(it);
    } else if (l->foundRatio() < config_.min_found_ratio ||
               (age >= 2 && l->numObservations() <= config_.min_observations)) {
      map_->retireLandmark(l);
      ++culled;
      it = recent_landmarks_.erase(it);
    } else if (age >= 3) {
      it = recent_landmarks_.erase(it);  // survived its probation
    } else {
      ++it;
    }
  }
  std::lock_guard<std::mutex> stats_lock(stats_mutex_);
  stats_.landmarks_culled += culled;
}

void LocalMapper::triangulateNewLandmarks(Keyframe* keyframe) {
  // A waiting keyframe stops the neighbour loop early (ORB-SLAM2's CheckNewKeyFrames).
  std::vector<std::shared_ptr<Landmark>> created =
      createNewLandmarks(map_, keyframe, camera_, pyramid_, config_.triangulation,
                         [this] { return queue_.moreWorkOrStopping(); });
  {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    stats_.landmarks_triangulated += created.size();
  }
  // On probation like the tracker's new landmarks (ORB-SLAM2's mlpRecentAddedMapPoints).
  recent_landmarks_.insert(recent_landmarks_.end(), std::make_move_iterator(created.begin()),
                           std::make_move_iterator(created.end()));
}

void LocalMapper::fuseWithNeighbours(Keyframe* keyframe) {
  std::unique_lock<std::shared_mutex> lock(map_->mutex());
  if (keyframe->bad()) return;
  std::vector<Keyframe*> targets;
  for (Keyframe* k : keyframe->bestCovisible(static_cast<size_t>(config_.fuse_neighbours))) {
    if (k->bad() || k->fuse_target_for_keyframe == keyframe->id) continue;
    targets.push_back(k);
    k->fuse_target_for_keyframe = keyframe->id;
  }
  const size_t first_ring = targets.size();
  for (size_t i = 0; i < first_ring; ++i) {
    for (Keyframe* k2 :
         targets[i]->bestCovisible(static_cast<size_t>(config_.fuse_second_neighbours))) {
      if (k2->bad() || k2 == keyframe || k2->fuse_target_for_keyframe == keyframe->id) continue;
      targets.push_back(k2);
      k2->fuse_target_for_keyframe = keyframe->id;
    }
  }
  int fused = 0;
  // The keyframe's landmarks into its neighbours...
  // (Held again per target: a fusion may have replaced some of the keyframe's landmarks.)
  for (Keyframe* target : targets) {
    fused += fuseLandmarks(map_, target, holdLandmarks(keyframe->landmarks()), config_.fuse_radius,
                           camera_, pyramid_);
  }
  // ... and the neighbours' landmarks into the keyframe.
  std::vector<Landmark*> theirs;
  for (Keyframe* target : targets) {
    for (Landmark* l : target->landmarks()) {
      if (l == nullptr || l->bad() || l->fuse_candidate_for_keyframe == keyframe->id) continue;
      l->fuse_candidate_for_keyframe = keyframe->id;
      theirs.push_back(l);
    }
  }
  fused +=
      fuseLandmarks(map_, keyframe, holdLandmarks(theirs), config_.fuse_radius, camera_, pyramid_);
  for (Landmark* l : keyframe->landmarks()) {
    if (l == nullptr || l->bad()) continue;
    l->updateDescriptor();
    l->updateNormalAndDepth(pyramid_);
  }
  keyframe->updateConnections();
  std::lock_guard<std::mutex> stats_lock(stats_mutex_);
  stats_.landmarks_fused += static_cast<uint64_t>(fused);
}

void LocalMapper::localBundleAdjustment(Keyframe* keyframe) {
  BundleAdjustmentProblem problem;
  problem.camera = StereoCameraModel{camera_.intrinsics.fx, camera_.intrinsics.fy,
                                     camera_.intrinsics.cx, camera_.intrinsics.cy, camera_.bf()};
  std::vector<Keyframe*> keyframes;
  std::vector<std::shared_ptr<Landmark>> landmarks;
  std::vector<std::pair<Keyframe*, uint32_t>> observation_of;  // per BA observation
  const float correction_px = map_->disparityCorrectionPx();
  int change_index = 0;
  size_t window_size = 0;
  {
    std::shared_lock<std::shared_mutex> lock(map_->mutex());
    if (keyframe->bad() || map_->numKeyframes() <= 2) return;
    if (map_->correctionPending()) {  // half of the map corrected: the next keyframe's BA
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.bundle_adjustments_discarded;
      return;
    }
    change_index = map_->changeIndex();
    // Window: the keyframe and its covisible keyframes, by shared landmarks (all of them, or
    // the best local_ba_max_keyframes).
    std::vector<Keyframe*> window{keyframe};
    keyframe->ba_local_for_keyframe = keyframe->id;
    const size_t max_window = config_.local_ba_max_keyframes > 0
                                  ? static_cast<size_t>(config_.local_ba_max_keyframes) + 1
                                  : SIZE_MAX;
    for (Keyframe* k : keyframe->covisibleByWeight()) {
      if (window.size() >= max_window) break;
      if (k->bad() || k->ba_local_for_keyframe == keyframe->id) continue;
      k->ba_local_for_keyframe = keyframe->id;
      window.push_back(k);
    }
    window_size = window.size();
    for (Keyframe* k : window) {
      for (Landmark* l : k->landmarks()) {
        if (l == nullptr || l->bad() || l->ba_local_for_keyframe == keyframe->id) continue;
        l->ba_local_for_keyframe = keyframe->id;
        landmarks.push_back(l->shared_from_this());
      }
    }
    // Fixed keyframes: see window landmarks, outside the window.
    std::vector<Keyframe*> fixed;
    for (const auto& l : landmarks) {
      for (const auto& [k, index] : l->observations()) {
        if (k->bad() || k->ba_local_for_keyframe == keyframe->id ||
            k->ba_fixed_for_keyframe == keyframe->id) {
          continue;
        }
        k->ba_fixed_for_keyframe = keyframe->id;
        fixed.push_back(k);
      }
    }
    // The first keyframe is the gauge: held fixed if it is in the window.
    std::map<const Keyframe*, int> keyframe_index;
    for (Keyframe* k : window) {
      keyframe_index[k] = static_cast<int>(keyframes.size());
      keyframes.push_back(k);
      problem.keyframes.push_back(BaKeyframe{static_cast<uint64_t>(k->id), k->T_C_G(), k->id == 0});
    }
    for (Keyframe* k : fixed) {
      keyframe_index[k] = static_cast<int>(keyframes.size());
      keyframes.push_back(k);
      problem.keyframes.push_back(BaKeyframe{static_cast<uint64_t>(k->id), k->T_C_G(), true});
    }
    bool any_fixed = false;
    for (const BaKeyframe& k : problem.keyframes) any_fixed = any_fixed || k.fixed;
    if (!any_fixed) return;  // no gauge (cannot happen with > 2 keyframes, kept for safety)
    for (size_t li = 0; li < landmarks.size(); ++li) {
      const Landmark& l = *landmarks[li];
      problem.landmarks.push_back(BaLandmark{l.id, l.position()});
      for (const auto& [k, index] : l.observations()) {
        const auto it = keyframe_index.find(k);
        if (it == keyframe_index.end()) continue;
        const FrameFeatures& f = k->features();
        BaObservation o;
        o.keyframe = it->second;
        o.landmark = static_cast<int>(li);
        static_cast<StereoMeasurement&>(o) = featureMeasurement(f, index, pyramid_, correction_px);
        problem.observations.push_back(o);
        observation_of.emplace_back(k, index);
      }
    }
  }
  if (problem.observations.empty()) return;
  const BundleAdjustmentResult result =
      bundleAdjust(problem, config_.bundle_adjustment, &abort_ba_);
  KeyframePoseBatch changed;
  {
    std::unique_lock<std::shared_mutex> lock(map_->mutex());
    if (map_->changeIndex() != change_index) {
      // A loop correction moved the map meanwhile: this solution is stale.
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.bundle_adjustments_discarded;
      return;
    }
    // Outlier observations leave the map (if they still exist).
    for (size_t o = 0; o < problem.observations.size(); ++o) {
      if (!result.outlier[o]) continue;
      auto [k, index] = observation_of[o];
      Landmark* l = landmarks[static_cast<size_t>(problem.observations[o].landmark)].get();
      if (k->landmark(index) == l) SparseMap::eraseObservation(k, index);
    }
    for (size_t i = 0; i < keyframes.size(); ++i) {
      if (problem.keyframes[i].fixed || keyframes[i]->bad()) continue;
      keyframes[i]->setPose(result.T_C_G[i]);
      changed.emplace_back(keyframes[i]->id, keyframes[i]->T_G_C());
    }
    map_->moveCulledKeyframes(&changed);
    for (size_t li = 0; li < landmarks.size(); ++li) {
      Landmark* l = landmarks[li].get();
      if (l->bad()) continue;
      if (l->observations().empty()) {
        map_->retireLandmark(l);
        continue;
      }
      l->setPosition(result.p_G[li]);
      l->updateNormalAndDepth(pyramid_);
    }
  }
  const size_t optimised =
      static_cast<size_t>(std::count_if(problem.keyframes.begin(), problem.keyframes.end(),
                                        [](const BaKeyframe& k) { return !k.fixed; }));
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.bundle_adjustments;
    if (result.aborted) ++stats_.bundle_adjustments_aborted;
    stats_.last_ba_ms = result.time_ms;
    stats_.largest_ba_window = std::max(stats_.largest_ba_window, window_size);
    stats_.last_ba_free_keyframes = optimised;
    stats_.last_ba_fixed_keyframes = problem.keyframes.size() - optimised;
    stats_.last_ba_landmarks = problem.landmarks.size();
    stats_.last_ba_observations = problem.observations.size();
  }
  if (on_poses_ && !changed.empty()) on_poses_(changed);
  if (config_.disparity_correction.enabled && !result.aborted &&
      ++local_bas_since_estimate_ >= disparity_correction_.estimateInterval()) {
    local_bas_since_estimate_ = 0;
    estimateDisparityOffset(problem, result, observation_of);
  }
}

void LocalMapper::estimateDisparityOffset(
    const BundleAdjustmentProblem& problem, const BundleAdjustmentResult& solution,
    const std::vector<std::pair<Keyframe*, uint32_t>>& observation_of) {
  const double start = threadCpuSeconds();
  // The window at the BA's solution, its inliers only, with the raw (matched) right columns;
  // a right column not from stereo matching (RGB-D's virtual one) leaves it mono.
  BundleAdjustmentProblem raw;
  raw.camera = problem.camera;
  raw.keyframes = problem.keyframes;
  for (size_t k = 0; k < raw.keyframes.size(); ++k) raw.keyframes[k].T_C_G = solution.T_C_G[k];
  raw.landmarks = problem.landmarks;
  for (size_t l = 0; l < raw.landmarks.size(); ++l) raw.landmarks[l].p_G = solution.p_G[l];
  raw.observations.reserve(problem.observations.size());
  bool any_stereo = false;
  for (size_t o = 0; o < problem.observations.size(); ++o) {
    if (solution.outlier[o]) continue;
    BaObservation observation = problem.observations[o];
    const FrameFeatures& f = observation_of[o].first->features();
    if (observation.u_right >= 0.0) {
      if (f.stereo_matched) {
        observation.u_right = f.right_u[observation_of[o].second] + f.disparity_correction_px;
        any_stereo = true;
      } else {
        observation.u_right = -1.0;
      }
    }
    raw.observations.push_back(observation);
  }
  if (!any_stereo) return;
  const DisparityOffsetEstimate estimate =
      cblox::estimateDisparityOffset(raw, config_.disparity_correction.solver);
  if (estimate.ok) {
    disparity_correction_.addEstimate(estimate.offset_px);
    map_->setDisparityCorrectionPx(disparity_correction_.correctionPx());
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++(estimate.ok ? stats_.disparity_offset_estimates : stats_.disparity_offset_failures);
  stats_.disparity_offset_seconds += threadCpuSeconds() - start;
}

void LocalMapper::cullKeyframes(Keyframe* keyframe) {
  std::unique_lock<std::shared_mutex> lock(map_->mutex());
  uint64_t culled = 0;
  for (Keyframe* k : keyframe->covisibleByWeight()) {
    if (k->id == 0 || k->bad()) continue;
    const FrameFeatures& f = k->features();
    int valid = 0, redundant = 0;
    for (size_t i = 0; i < f.size(); ++i) {
      Landmark* l = k->landmark(i);
      if (l == nullptr || l->bad()) continue;
      if (!(f.depth[i] > 0.0f) || f.depth[i] > camera_.close_depth_m) continue;
      ++valid;
      if (l->numObservations() <= 3) continue;
      const int level = f.keypoints[i].octave;
      int seen = 0;
      for (const auto& [other, index] : l->observations()) {
        if (other == k) continue;
        if (other->features().keypoints[index].octave <= level + 1 && ++seen >= 3) break;
      }
      if (seen >= 3) ++redundant;
    }
    if (valid > 0 && redundant > config_.redundant_ratio * valid) {
      map_->cullKeyframe(k);
      if (k->bad()) ++culled;
    }
  }
  std::lock_guard<std::mutex> stats_lock(stats_mutex_);
  stats_.keyframes_culled += culled;
}

}  // namespace cblox
