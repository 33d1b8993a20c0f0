#include "core/tracking/slam_system.h"

#include <algorithm>
#include <stdexcept>

#include "core/common/thread_name.h"

namespace cblox {

std::string SlamSystemConfig::validate() const {
  if (std::string e = frames.validate(); !e.empty()) return "frames: " + e;
  if (std::string e = tracker.validate(); !e.empty()) return "tracker: " + e;
  if (std::string e = local_mapping.validate(); !e.empty()) return "local_mapping: " + e;
  if (std::string e = loop_closing.validate(); !e.empty()) return "loop_closing: " + e;
  return "";
}

namespace {
const SlamSystemConfig& validated(const SlamSystemConfig& config) {
  if (std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("SlamSystem: " + e);
  }
  return config;
}
}  // namespace

SlamSystem::SlamSystem(const TrackingCamera& camera, const SlamSystemConfig& config,
                       const BinaryVocabulary* vocabulary, ThreadStartHook on_thread_start)
    : camera_(camera),
      config_(validated(config)),
      vocabulary_(vocabulary),
      builder_(camera, config.frames, vocabulary),
      local_mapper_(&map_, camera, builder_.pyramid(), config.local_mapping),
      tracker_(&map_, camera, builder_.pyramid(), config.tracker,
               vocabulary != nullptr ? &database_ : nullptr, &sink_, vocabulary) {
  if (vocabulary != nullptr && config.loop_closing_enabled) {
    loop_closer_ = std::make_unique<LoopCloser>(&map_, &database_, camera, builder_.pyramid(),
                                                config.loop_closing);
    loop_closer_->setPoseCallback([this](const KeyframePoseBatch& batch, bool global_ba) {
      if (on_poses_) {
        on_poses_(batch, global_ba ? PoseUpdateReason::kGlobalBundleAdjustment
                                   : PoseUpdateReason::kLoopCorrection);
      }
    });
    loop_closer_->setLoopCallback([this](const LoopClosureEvent& event) {
      if (on_loop_) on_loop_(event);
    });
  }
  local_mapper_.setKeyframeCallback([this](Keyframe* keyframe) {
    if (loop_closer_) {
      loop_closer_->insertKeyframe(keyframe);  // it adds the keyframe to the database
    } else if (vocabulary_ != nullptr) {
      // Processed keyframes become relocalization candidates.
      std::shared_lock<std::shared_mutex> lock(map_.mutex());
      if (!keyframe->bad()) database_.add(keyframe->id, keyframe->features().bow);
    }
  });
  local_mapper_.setPoseCallback([this](const KeyframePoseBatch& batch) {
    if (on_poses_) on_poses_(batch, PoseUpdateReason::kLocalBundleAdjustment);
  });
  local_mapping_thread_ = std::thread([this, on_thread_start] {
    nameThisThread("cblox-localmap");
    if (on_thread_start) on_thread_start("local mapping");
    local_mapper_.run();
  });
  if (loop_closer_) {
    loop_closing_thread_ = std::thread([this, on_thread_start] {
      nameThisThread("cblox-loop");
      if (on_thread_start) on_thread_start("loop closing");
      loop_closer_->run();
    });
  }
}

SlamSystem::~SlamSystem() { stop(); }

void SlamSystem::stop() {
  if (stopped_) return;
  stopped_ = true;
  local_mapper_.stop();
  if (local_mapping_thread_.joinable()) local_mapping_thread_.join();
  if (loop_closer_) loop_closer_->stop();
  if (loop_closing_thread_.joinable()) loop_closing_thread_.join();
}

void SlamSystem::waitUntilIdle() {
  local_mapper_.waitUntilIdle();
  if (loop_closer_) loop_closer_->waitUntilIdle();
}

TrackingResult SlamSystem::trackStereo(uint64_t frame_id, int64_t timestamp_ns,
                                       const GrayImage& left, const GrayImage& right,
                                       const std::optional<Transformationd>& T_C_G_initial) {
  auto features = builder_.fromStereo(left, right, map_.disparityCorrectionPx());
  return tracker_.track(frame_id, timestamp_ns, std::move(features), T_C_G_initial);
}

TrackingResult SlamSystem::trackRgbd(uint64_t frame_id, int64_t timestamp_ns, const GrayImage& gray,
                                     const DepthImage& depth,
                                     const std::optional<Transformationd>& T_C_G_initial) {
  auto features = builder_.fromRgbd(gray, depth);
  return tracker_.track(frame_id, timestamp_ns, std::move(features), T_C_G_initial);
}

SparseMapSnapshot SlamSystem::snapshot() const {
  std::shared_lock<std::shared_mutex> lock(map_.mutex());
  return takeSparseMapSnapshot(map_);
}

void SlamSystem::restore(const SparseMapSnapshot& snapshot, KeyframeId next_keyframe_id,
                         LandmarkId next_landmark_id) {
  if (tracker_.state() != TrackingState::kNotInitialized) {
    throw std::invalid_argument("cannot restore a sparse map after frames were tracked");
  }
  SparseMapSnapshot indexed = snapshot;
  for (KeyframeSnapshot& k : indexed.keyframes) {
    if (k.features->size() == 0) continue;
    auto features = std::make_shared<FrameFeatures>(*k.features);
    builder_.index(features.get());
    k.features = std::move(features);
  }
  {
    std::unique_lock<std::shared_mutex> lock(map_.mutex());
    map_.restore(indexed, builder_.pyramid().numLevels(), next_keyframe_id, next_landmark_id);
  }
  if (vocabulary_ != nullptr) {
    std::shared_lock<std::shared_mutex> lock(map_.mutex());
    for (const Keyframe* keyframe : map_.keyframes()) {
      database_.add(keyframe->id, keyframe->features().bow);
    }
  }
  tracker_.resumeLost();
}

void SlamSystem::AnnouncingSink::insertKeyframe(Keyframe* keyframe) {
  if (system_->on_keyframe_) {
    // Called by the tracker right after it made the keyframe, before local mapping has it;
    // the shared lock still guards against the loop-closing thread.
    KeyframeInfo info;
    {
      std::shared_lock<std::shared_mutex> lock(system_->map_.mutex());
      info.id = keyframe->id;
      info.frame_id = keyframe->frame_id;
      info.timestamp_ns = keyframe->timestamp_ns;
      info.T_G_K = keyframe->T_G_C();
      for (const Landmark* l : keyframe->landmarks()) {
        if (l != nullptr && !l->bad()) info.landmark_ids.push_back(l->id);
      }
    }
    std::sort(info.landmark_ids.begin(), info.landmark_ids.end());
    system_->on_keyframe_(info);
  }
  system_->local_mapper_.insertKeyframe(keyframe);
}

}  // namespace cblox
