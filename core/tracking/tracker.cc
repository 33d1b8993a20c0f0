#include "core/tracking/tracker.h"

#include <algorithm>
#include <chrono>
#include <set>
#include <stdexcept>
#include <unordered_set>
#include <utility>

#include <opencv2/calib3d.hpp>

#include "core/optimization/pose_optimizer.h"
#include "core/tracking/feature_matcher.h"
#include "core/tracking/feature_measurement.h"

namespace cblox {
namespace {

// Relocalization's guided search windows (projectLandmark's th: radius th * 2.5-4 px times
// the level scale), ORB-SLAM2's 10 px and 3 px windows.
constexpr float kRelocalizationWideWindow = 3.0f;
constexpr float kRelocalizationNarrowWindow = 1.0f;

}  // namespace

const char* trackingStateName(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized:
      return "NOT_INITIALIZED";
    case TrackingState::kOk:
      return "OK";
    case TrackingState::kLost:
      return "LOST";
  }
  return "?";
}

const char* keyframeReasonName(KeyframeReason reason) {
  switch (reason) {
    case KeyframeReason::kNone:
      return "none";
    case KeyframeReason::kMaxFrames:
      return "max_frames";
    case KeyframeReason::kClosePoints:
      return "close_points";
    case KeyframeReason::kWeakTracking:
      return "weak_tracking";
    case KeyframeReason::kMapperIdle:
      return "mapper_idle";
  }
  return "?";
}

Tracker::Tracker(SparseMap* map, const TrackingCamera& camera, const ScalePyramid& pyramid,
                 const TrackerConfig& config, const KeyframeDatabase* database, KeyframeSink* sink,
                 const BinaryVocabulary* vocabulary)
    : map_(map),
      camera_(camera),
      pyramid_(pyramid),
      config_(config),
      database_(database),
      sink_(sink),
      vocabulary_(vocabulary) {
  if (map == nullptr) throw std::invalid_argument("Tracker: map is null");
  if (database != nullptr && vocabulary == nullptr) {
    throw std::invalid_argument(
        "Tracker: a keyframe database (relocalization) needs the vocabulary of its BoW vectors");
  }
  if (std::string e = camera.validate(); !e.empty()) {
    throw std::invalid_argument("Tracker: camera: " + e);
  }
  if (std::string e = config.validate(); !e.empty()) throw std::invalid_argument("Tracker: " + e);
  model_ = StereoCameraModel{camera.intrinsics.fx, camera.intrinsics.fy, camera.intrinsics.cx,
                             camera.intrinsics.cy, camera.bf()};
}

TrackingResult Tracker::track(uint64_t frame_id, int64_t timestamp_ns,
                              std::shared_ptr<FrameFeatures> features,
                              const std::optional<Transformationd>& T_C_G_initial) {
  const auto start = std::chrono::steady_clock::now();
  TrackingResult result;
  current_features_ = features;
  current_ = Frame(frame_id, timestamp_ns, std::move(features));
  current_index_ = ++frames_processed_;
  KeyframeReason create_keyframe = KeyframeReason::kNone;
  // Takes a lock of the map's mutex, adding the time it waited to result.map_wait_ms.
  const auto waitFor = [&result](auto lock) {
    const auto asked = std::chrono::steady_clock::now();
    lock.lock();
    result.map_wait_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - asked).count();
    return lock;
  };
  using SharedLock = std::shared_lock<std::shared_mutex>;
  using UniqueLock = std::unique_lock<std::shared_mutex>;
  {
    const SharedLock lock = waitFor(SharedLock(map_->mutex(), std::defer_lock));
    if (map_->changeIndex() != map_change_index_) {
      map_change_index_ = map_->changeIndex();
      result.map_corrected = state_ != TrackingState::kNotInitialized;
    }
    if (state_ == TrackingState::kNotInitialized) {
      // Initialisation needs the exclusive lock: done below.
      if (current_.features->size() == 0) result.reason = "no features";
    } else {
      bool ok = false;
      bool relocalized = false;
      if (state_ == TrackingState::kOk) {
        replaceRetiredInLastFrame();
        updateLastFramePose();
        const bool just_relocalized =
            ever_relocalized_ && current_index_ < last_relocalization_index_ + 2;
        FrameSearchCounts counts;
        const bool motion = velocity_.has_value() && !just_relocalized;
        if (motion) ok = trackWithMotionModel(&counts.motion_matches, &counts.motion_inliers);
        if (!ok) ok = trackReferenceKeyframe(&counts.reference_matches, &counts.reference_inliers);
        if (!ok) result.reason = frameSearchFailure(counts);
      } else {
        ok = relocalize();
        relocalized = ok;
        if (!ok) result.reason = "lost: relocalization found no consistent keyframe";
      }
      current_.reference_keyframe = reference_keyframe_;
      if (ok) {
        ok = trackLocalMap(&result);
        if (!ok && result.reason.empty()) result.reason = "too few inliers in the local map";
      }
      state_ = ok ? TrackingState::kOk : TrackingState::kLost;
      result.state = state_;
      result.relocalized = relocalized;
      if (ok) {
        result.T_C_G = current_.T_C_G;
        if (last_frame_.T_C_G) velocity_ = *current_.T_C_G * last_frame_.T_C_G->inverse();
        create_keyframe = needNewKeyframe(result.inliers);
        if (reference_keyframe_ != nullptr)
          T_current_reference_ = *current_.T_C_G * reference_keyframe_->T_G_C();
      } else {
        velocity_.reset();
      }
    }
  }
  if (state_ == TrackingState::kNotInitialized && result.reason.empty()) {
    computeBow();  // before the first keyframe is shared (not under the map's lock)
    const UniqueLock lock = waitFor(UniqueLock(map_->mutex(), std::defer_lock));
    if (initialize(T_C_G_initial, &result)) {
      state_ = TrackingState::kOk;
      result.state = state_;
      result.initialized = true;
      result.T_C_G = current_.T_C_G;
    }
  } else if (create_keyframe != KeyframeReason::kNone) {
    if (after_tracking_hook_) after_tracking_hook_(true);
    computeBow();
    const UniqueLock lock = waitFor(UniqueLock(map_->mutex(), std::defer_lock));
    followReferenceKeyframe();
    result.T_C_G = current_.T_C_G;
    result.new_keyframe = createKeyframe();
    if (result.new_keyframe != nullptr) result.keyframe_reason = create_keyframe;
  } else if (after_tracking_hook_ && state_ == TrackingState::kOk) {
    after_tracking_hook_(false);
  }
  if (result.new_keyframe != nullptr && sink_ != nullptr)
    sink_->insertKeyframe(result.new_keyframe);
  // Outliers do not carry over to the next frame's motion-model search.
  for (size_t i = 0; i < current_.size(); ++i) {
    if (current_.outlier[i]) current_.landmarks[i] = nullptr;
  }
  if (result.state == TrackingState::kOk && reference_keyframe_ != nullptr) {
    result.reference_keyframe = reference_keyframe_->id;
  }
  last_frame_ = current_;
  current_features_.reset();  // shared from here on (last frame, maybe a keyframe)
  if (result.state == TrackingState::kOk && current_.T_C_G && reference_keyframe_ != nullptr) {
    // As read under the lock the frame was tracked with (or identity to the keyframe it just
    // made): a pose the map has moved since is not mixed with the reference's new one.
    last_reference_ = reference_keyframe_;
    T_last_reference_ = result.new_keyframe != nullptr ? Transformationd() : T_current_reference_;
  } else {
    last_reference_ = nullptr;
  }
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void Tracker::computeBow() {
  if (vocabulary_ == nullptr || current_features_ == nullptr) return;
  FrameFeatures& f = *current_features_;
  if (!f.bow.empty() || f.descriptors.empty()) return;
  vocabulary_->transform(f.descriptors, &f.bow, &f.feature_vector);
}

bool Tracker::initialize(const std::optional<Transformationd>& T_C_G_initial,
                         TrackingResult* result) {
  const FrameFeatures& f = *current_.features;
  size_t with_depth = 0;
  for (size_t i = 0; i < f.size(); ++i) with_depth += f.hasDepth(i) ? 1 : 0;
  if (static_cast<int>(with_depth) < config_.min_features_to_initialize) {
    result->reason = "initialisation needs " + std::to_string(config_.min_features_to_initialize) +
                     " features with depth, the frame has " + std::to_string(with_depth);
    return false;
  }
  const Transformationd T_C_G = T_C_G_initial.value_or(Transformationd());
  current_.T_C_G = T_C_G;
  Keyframe* keyframe =
      map_->addKeyframe(current_.id, current_.timestamp_ns, current_.features, T_C_G);
  const Transformationd T_G_C = T_C_G.inverse();
  for (size_t i = 0; i < f.size(); ++i) {
    if (!f.hasDepth(i)) continue;
    std::shared_ptr<Landmark> landmark =
        map_->addLandmark(T_G_C * f.unproject(i, camera_), keyframe);
    SparseMap::addObservation(keyframe, static_cast<uint32_t>(i), landmark.get());
    landmark->updateDescriptor();
    landmark->updateNormalAndDepth(pyramid_);
    current_.landmarks[i] = std::move(landmark);
  }
  reference_keyframe_ = keyframe;
  last_keyframe_index_ = current_index_;
  last_keyframe_rotation_ = current_.T_C_G->rotation();
  local_keyframes_ = {keyframe};
  result->new_keyframe = keyframe;
  result->inliers = current_.numInlierMatches();
  return true;
}

void Tracker::replaceRetiredInLastFrame() {
  for (auto& landmark : last_frame_.landmarks) {
    if (landmark && landmark->bad() && landmark->replacement()) {
      std::shared_ptr<Landmark> by = landmark->replacement();
      while (by->bad() && by->replacement()) by = by->replacement();
      landmark = by->bad() ? nullptr : by;
    }
  }
}

int Tracker::optimizeCurrentPose() {
  std::vector<PoseObservation> observations;
  std::vector<size_t> index;
  const FrameFeatures& f = *current_.features;
  for (size_t i = 0; i < current_.size(); ++i) {
    const std::shared_ptr<Landmark>& landmark = current_.landmarks[i];
    if (!landmark) continue;
    observations.push_back(poseObservation(f, i, pyramid_, landmark->position()));
    index.push_back(i);
  }
  if (observations.size() < 3) return 0;
  const PoseOptimizationResult r = optimizePose(model_, *current_.T_C_G, observations);
  current_.T_C_G = r.T_C_G;
  for (size_t k = 0; k < index.size(); ++k) current_.outlier[index[k]] = r.inlier[k] ? 0 : 1;
  return r.num_inliers;
}

// Drops outlier matches (they are not used again for this frame).
namespace {
int discardOutliers(Frame* frame) {
  int inliers = 0;
  for (size_t i = 0; i < frame->size(); ++i) {
    if (!frame->landmarks[i]) continue;
    if (frame->outlier[i]) {
      frame->landmarks[i] = nullptr;
      frame->outlier[i] = 0;
    } else if (frame->landmarks[i]->numObservations() > 0) {
      ++inliers;
    }
  }
  return inliers;
}
}  // namespace

bool Tracker::trackWithMotionModel(int* matches, int* inliers) {
  current_.T_C_G = *velocity_ * *last_frame_.T_C_G;
  current_.clearMatches();
  FeatureMatcherConfig matcher;
  matcher.nn_ratio = 0.9f;
  *matches = searchLastFrame(&current_, last_frame_, config_.last_frame_search_radius, camera_,
                             pyramid_, matcher);
  if (*matches < config_.min_motion_model_matches) {
    current_.clearMatches();
    *matches = searchLastFrame(&current_, last_frame_, 2.0f * config_.last_frame_search_radius,
                               camera_, pyramid_, matcher);
  }
  if (*matches < config_.min_motion_model_matches) return false;
  optimizeCurrentPose();
  *inliers = discardOutliers(&current_);
  return *inliers >= config_.min_pose_inliers;
}

std::string Tracker::frameSearchFailure(const FrameSearchCounts& c) {
  const auto counts = [](int matches, int inliers) {
    if (matches < 0) return std::string("not tried");
    return std::to_string(matches) + " matches" +
           (inliers >= 0 ? ", " + std::to_string(inliers) + " inliers" : std::string());
  };
  return "too few matches with the last frame (" + counts(c.motion_matches, c.motion_inliers) +
         ") and the reference keyframe (" + counts(c.reference_matches, c.reference_inliers) + ")";
}

bool Tracker::trackReferenceKeyframe(int* matches, int* inliers) {
  if (reference_keyframe_ == nullptr) return false;
  current_.clearMatches();
  current_.T_C_G = last_frame_.T_C_G ? *last_frame_.T_C_G : reference_keyframe_->T_C_G();
  computeBow();
  int n = 0;
  if (!current_.features->feature_vector.empty() &&
      !reference_keyframe_->features().feature_vector.empty()) {
    FeatureMatcherConfig matcher;
    matcher.nn_ratio = 0.7f;
    std::vector<Landmark*> matched;
    n = searchByBow(*reference_keyframe_, *current_.features, matcher, &matched);
    for (size_t i = 0; i < matched.size(); ++i) {
      if (matched[i] != nullptr) current_.landmarks[i] = matched[i]->shared_from_this();
    }
  } else {
    // No vocabulary: the reference keyframe's landmarks projected at the last pose, in a
    // wide window.
    std::vector<LandmarkProjection> projections;
    for (Landmark* l : reference_keyframe_->landmarks()) {
      if (l == nullptr || l->bad()) continue;
      if (const auto p = projectLandmark(l, *current_.T_C_G, camera_, pyramid_)) {
        projections.push_back(*p);
      }
    }
    FeatureMatcherConfig matcher;
    matcher.nn_ratio = 0.7f;
    n = searchLocalLandmarks(&current_, projections, 2.0f * config_.last_frame_search_radius,
                             matcher, pyramid_);
  }
  *matches = n;
  if (n < config_.min_reference_matches) return false;
  optimizeCurrentPose();
  *inliers = discardOutliers(&current_);
  return *inliers >= config_.min_pose_inliers;
}

void Tracker::updateLocalMap() {
  // Keyframes that observe the frame's landmarks, by number of shared landmarks (counted in
  // the keyframes themselves, then visited in id order as ORB-SLAM2's std::map would).
  const uint64_t stamp = current_index_;
  observers_.clear();
  for (size_t i = 0; i < current_.size(); ++i) {
    const std::shared_ptr<Landmark>& landmark = current_.landmarks[i];
    if (!landmark) continue;
    if (landmark->bad()) {
      current_.landmarks[i] = nullptr;
      continue;
    }
    for (const auto& [keyframe, index] : landmark->observations()) {
      if (keyframe->track_counted_frame != stamp) {
        keyframe->track_counted_frame = stamp;
        keyframe->track_shared_landmarks = 0;
        observers_.push_back(keyframe);
      }
      ++keyframe->track_shared_landmarks;
    }
  }
  std::sort(observers_.begin(), observers_.end(), KeyframeIdLess{});
  local_keyframes_.clear();
  Keyframe* best = nullptr;
  int best_count = 0;
  for (Keyframe* keyframe : observers_) {
    if (keyframe->bad()) continue;
    const int count = keyframe->track_shared_landmarks;
    if (count > best_count) {
      best_count = count;
      best = keyframe;
    }
    local_keyframes_.push_back(keyframe);
    keyframe->track_reference_frame = stamp;
  }
  const size_t first_ring = local_keyframes_.size();
  auto addKeyframe = [&](Keyframe* k) {
    if (k == nullptr || k->bad() || k->track_reference_frame == stamp) return false;
    k->track_reference_frame = stamp;
    local_keyframes_.push_back(k);
    return true;
  };
  for (size_t i = 0; i < first_ring; ++i) {
    if (static_cast<int>(local_keyframes_.size()) >= config_.max_local_keyframes) break;
    Keyframe* k = local_keyframes_[i];
    for (Keyframe* neighbour : k->bestCovisible(10)) {
      if (addKeyframe(neighbour)) break;
    }
    for (Keyframe* child : k->children()) {
      if (addKeyframe(child)) break;
    }
    addKeyframe(k->parent());
  }
  if (best != nullptr) {
    reference_keyframe_ = best;
    current_.reference_keyframe = best;
  }
  // Their landmarks.
  local_landmarks_.clear();
  for (Keyframe* k : local_keyframes_) {
    for (Landmark* l : k->landmarks()) {
      if (l == nullptr || l->bad() || l->track_reference_frame == stamp) continue;
      l->track_reference_frame = stamp;
      local_landmarks_.push_back(l);
    }
  }
}

int Tracker::searchLocalMap() {
  const uint64_t stamp = current_index_;
  for (const auto& landmark : current_.landmarks) {
    if (!landmark || landmark->bad()) continue;
    landmark->increaseVisible();
    landmark->last_seen_frame = stamp;
  }
  std::vector<LandmarkProjection> projections;
  for (Landmark* landmark : local_landmarks_) {
    if (landmark->last_seen_frame == stamp || landmark->bad()) continue;
    if (const auto p = projectLandmark(landmark, *current_.T_C_G, camera_, pyramid_)) {
      landmark->increaseVisible();
      projections.push_back(*p);
    }
  }
  if (projections.empty()) return 0;
  const bool just_relocalized =
      ever_relocalized_ && current_index_ < last_relocalization_index_ + 2;
  const float radius =
      just_relocalized ? config_.relocalized_search_radius : config_.local_map_search_radius;
  FeatureMatcherConfig matcher;
  matcher.nn_ratio = 0.8f;
  return searchLocalLandmarks(&current_, projections, radius, matcher, pyramid_);
}

bool Tracker::trackLocalMap(TrackingResult* result) {
  updateLocalMap();
  searchLocalMap();
  optimizeCurrentPose();
  int inliers = 0;
  for (size_t i = 0; i < current_.size(); ++i) {
    const std::shared_ptr<Landmark>& landmark = current_.landmarks[i];
    if (!landmark || current_.outlier[i]) continue;
    landmark->increaseFound();
    if (landmark->numObservations() > 0) ++inliers;
  }
  result->inliers = inliers;
  const bool recent_relocalization =
      ever_relocalized_ &&
      current_index_ <
          last_relocalization_index_ + static_cast<uint64_t>(config_.max_frames_between_keyframes);
  if (recent_relocalization && inliers < config_.min_local_map_inliers_after_relocalization) {
    result->reason = "too few inliers after relocalization: " + std::to_string(inliers);
    return false;
  }
  if (inliers < config_.min_local_map_inliers) {
    result->reason = "too few inliers in the local map: " + std::to_string(inliers);
    return false;
  }
  return true;
}

KeyframeReason Tracker::needNewKeyframe(int inliers) const {
  const size_t num_keyframes = map_->numKeyframes();
  const uint64_t max_frames = static_cast<uint64_t>(config_.max_frames_between_keyframes);
  if (ever_relocalized_ && current_index_ < last_relocalization_index_ + max_frames &&
      num_keyframes > max_frames) {
    return KeyframeReason::kNone;
  }
  const int min_observations = num_keyframes <= 2 ? 2 : 3;
  const int reference_matches = reference_keyframe_ != nullptr
                                    ? reference_keyframe_->numTrackedLandmarks(min_observations)
                                    : 0;
  const bool idle = sink_ == nullptr || sink_->acceptsKeyframes();
  const FrameFeatures& f = *current_.features;
  int tracked_close = 0, untracked_close = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (!(f.depth[i] > 0.0f) || f.depth[i] >= camera_.close_depth_m) continue;
    if (current_.landmarks[i] && !current_.outlier[i]) {
      ++tracked_close;
    } else {
      ++untracked_close;
    }
  }
  const bool need_close = tracked_close < config_.tracked_close_min &&
                          untracked_close > config_.untracked_close_min &&
                          closePointGapPassed(inliers);
  const double ratio = num_keyframes < 2 ? 0.4 : config_.reference_ratio;
  const bool c1a = current_index_ >= last_keyframe_index_ + max_frames;
  const bool c1b =
      current_index_ >=
          last_keyframe_index_ + static_cast<uint64_t>(config_.min_frames_between_keyframes) &&
      idle;
  const bool weak = inliers < reference_matches * 0.25;
  const bool c2 = (inliers < reference_matches * ratio || need_close) && inliers > 15;
  if (!((c1a || c1b || weak || need_close) && c2)) return KeyframeReason::kNone;
  const KeyframeReason reason = c1a          ? KeyframeReason::kMaxFrames
                                : need_close ? KeyframeReason::kClosePoints
                                : weak       ? KeyframeReason::kWeakTracking
                                             : KeyframeReason::kMapperIdle;
  if (idle) return reason;
  if (sink_ != nullptr) {
    sink_->interruptBundleAdjustment();
    return sink_->queuedKeyframes() < 3 ? reason : KeyframeReason::kNone;
  }
  return reason;
}

bool Tracker::closePointGapPassed(int inliers) const {
  if (inliers < config_.close_points_gap_min_inliers) return true;
  if (current_index_ >=
      last_keyframe_index_ + static_cast<uint64_t>(config_.close_points_min_frames)) {
    return true;
  }
  return config_.close_points_turn_deg > 0.0 &&
         current_.T_C_G->rotation().angularDistance(last_keyframe_rotation_) >
             config_.close_points_turn_deg * M_PI / 180.0;
}

Keyframe* Tracker::createKeyframe() {
  const FrameFeatures& f = *current_.features;
  Keyframe* keyframe =
      map_->addKeyframe(current_.id, current_.timestamp_ns, current_.features, *current_.T_C_G);
  for (size_t i = 0; i < current_.size(); ++i) {
    const std::shared_ptr<Landmark>& landmark = current_.landmarks[i];
    if (!landmark || current_.outlier[i] || landmark->bad()) continue;
    if (landmark->indexIn(keyframe) >= 0) continue;
    SparseMap::addObservation(keyframe, static_cast<uint32_t>(i), landmark.get());
  }
  // New landmarks from the closest unmatched features with depth.
  std::vector<std::pair<float, size_t>> by_depth;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.hasDepth(i)) by_depth.emplace_back(f.depth[i], i);
  }
  std::sort(by_depth.begin(), by_depth.end());
  const Transformationd T_G_C = current_.T_C_G->inverse();
  int points = 0;
  for (const auto& [depth, i] : by_depth) {
    const bool matched =
        current_.landmarks[i] && !current_.outlier[i] && !current_.landmarks[i]->bad();
    if (!matched) {
      std::shared_ptr<Landmark> landmark =
          map_->addLandmark(T_G_C * f.unproject(i, camera_), keyframe);
      SparseMap::addObservation(keyframe, static_cast<uint32_t>(i), landmark.get());
      landmark->updateDescriptor();
      landmark->updateNormalAndDepth(pyramid_);
      current_.landmarks[i] = std::move(landmark);
      current_.outlier[i] = 0;
    }
    ++points;
    if (depth > camera_.close_depth_m && points > config_.min_new_landmarks_per_keyframe) break;
  }
  keyframe->updateConnections();
  reference_keyframe_ = keyframe;
  current_.reference_keyframe = keyframe;
  last_keyframe_index_ = current_index_;
  last_keyframe_rotation_ = current_.T_C_G->rotation();
  return keyframe;
}

void Tracker::resumeLost() {
  std::shared_lock<std::shared_mutex> lock(map_->mutex());
  state_ = TrackingState::kLost;
  map_change_index_ = map_->changeIndex();
  velocity_.reset();
  reference_keyframe_ = nullptr;
  last_reference_ = nullptr;
}

bool Tracker::relocalize() {
  if (database_ == nullptr) return false;
  computeBow();
  if (current_.features->bow.empty()) return false;
  const std::vector<PlaceCandidate> candidates = database_->queryRelocalizationCandidates(
      current_.features->bow, static_cast<size_t>(config_.max_relocalization_candidates));
  const FrameFeatures& f = *current_.features;
  FeatureMatcherConfig matcher;
  matcher.nn_ratio = 0.75f;
  const PinholeIntrinsics& k = camera_.intrinsics;
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  for (const PlaceCandidate& candidate : candidates) {
    Keyframe* keyframe = map_->keyframe(candidate.id);
    if (keyframe == nullptr || keyframe->bad()) continue;
    std::vector<Landmark*> matches;
    if (searchByBow(*keyframe, f, matcher, &matches) < config_.min_relocalization_matches) {
      continue;
    }
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    std::vector<size_t> index;
    for (size_t i = 0; i < matches.size(); ++i) {
      if (matches[i] == nullptr) continue;
      const Eigen::Vector3d& p = matches[i]->position();
      object.emplace_back(p.x(), p.y(), p.z());
      image.emplace_back(f.keypoints[i].u, f.keypoints[i].v);
      index.push_back(i);
    }
    cv::Mat rvec, tvec;
    std::vector<int> inliers;
    if (!cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false,
                            config_.pnp_iterations,
                            static_cast<float>(config_.pnp_reprojection_error_px), 0.99, inliers,
                            cv::SOLVEPNP_EPNP) ||
        static_cast<int>(inliers.size()) < config_.min_pose_inliers) {
      continue;
    }
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    Eigen::Matrix3d R_C_G;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R_C_G(r, c) = R(r, c);
    }
    current_.clearMatches();
    for (const int i : inliers) {
      current_.landmarks[index[static_cast<size_t>(i)]] =
          matches[index[static_cast<size_t>(i)]]->shared_from_this();
    }
    current_.T_C_G = Transformationd::fromMatrix([&] {
      Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
      T.topLeftCorner<3, 3>() = R_C_G;
      T.topRightCorner<3, 1>() =
          Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
      return T;
    }());
    optimizeCurrentPose();
    int good = discardOutliers(&current_);
    if (good < config_.min_pose_inliers) continue;
    // ORB-SLAM2's guided search: too few PnP inliers to trust the pose are topped up with
    // the candidate's other landmarks projected at it, first in a wide window, then (when
    // close) in a narrow one; the candidate is accepted only with enough inliers.
    for (const float window : {kRelocalizationWideWindow, kRelocalizationNarrowWindow}) {
      if (good >= config_.min_local_map_inliers_after_relocalization) break;
      if (searchKeyframeLandmarks(*keyframe, window) == 0) break;
      optimizeCurrentPose();
      good = discardOutliers(&current_);
    }
    if (good < config_.min_local_map_inliers_after_relocalization) continue;
    reference_keyframe_ = keyframe;
    last_relocalization_index_ = current_index_;
    ever_relocalized_ = true;
    velocity_.reset();
    return true;
  }
  return false;
}

int Tracker::searchKeyframeLandmarks(const Keyframe& keyframe, float th) {
  std::unordered_set<const Landmark*> held;
  for (const auto& m : current_.landmarks) held.insert(m.get());
  std::vector<LandmarkProjection> projections;
  for (Landmark* l : keyframe.landmarks()) {
    if (l == nullptr || l->bad() || held.count(l) > 0) continue;
    if (const auto p = projectLandmark(l, *current_.T_C_G, camera_, pyramid_)) {
      projections.push_back(*p);
    }
  }
  FeatureMatcherConfig matcher;
  matcher.nn_ratio = 0.9f;
  return searchLocalLandmarks(&current_, projections, th, matcher, pyramid_);
}

void Tracker::followReferenceKeyframe() {
  if (reference_keyframe_ == nullptr || !current_.T_C_G) return;
  current_.T_C_G = T_current_reference_ * reference_keyframe_->T_C_G();
}

void Tracker::updateLastFramePose() {
  if (last_reference_ == nullptr || !last_frame_.T_C_G) return;
  last_frame_.T_C_G = T_last_reference_ * last_reference_->T_C_G();
}

}  // namespace cblox
