#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/geometry/image.h"
#include "core/tracking/frame_builder.h"
#include "core/tracking/local_mapper.h"
#include "core/tracking/loop_closer.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracker.h"
#include "core/vocabulary/binary_vocabulary.h"
#include "core/vocabulary/keyframe_database.h"

namespace cblox {

/// Settings of the whole sparse SLAM system.
struct SlamSystemConfig {
  FrameBuilderConfig frames;
  TrackerConfig tracker;
  LocalMapperConfig local_mapping;
  /// Loop closing runs when a vocabulary is given and this is true.
  bool loop_closing_enabled = true;
  LoopCloserConfig loop_closing;
  std::string validate() const;
};

/// A new keyframe as the rest of the system sees it (CBLOX_KEYFRAME).
struct KeyframeInfo {
  KeyframeId id = 0;
  uint64_t frame_id = 0;
  int64_t timestamp_ns = 0;
  Transformationd T_G_K;
  std::vector<LandmarkId> landmark_ids;  ///< landmarks it observes, ascending
};

/// Why keyframe poses changed (the reasons of keyframe_pose_batch_t).
enum class PoseUpdateReason { kLocalBundleAdjustment, kLoopCorrection, kGlobalBundleAdjustment };

/// The sparse SLAM system: the tracker (run on the caller's thread, one frame at a time),
/// local mapping and loop closing on threads of their own, and the keyframe database for
/// relocalization and place recognition.
///
/// Thread-safety: trackStereo / trackRgbd from one thread (the tracking thread). The
/// callbacks run on the tracking thread (keyframes) and on the local mapping thread (pose
/// updates), without locks held; they must be thread-safe with respect to each other.
class SlamSystem {
 public:
  using KeyframeCallback = std::function<void(const KeyframeInfo&)>;
  using PoseCallback = std::function<void(const KeyframePoseBatch&, PoseUpdateReason)>;
  /// Runs first on each thread the system starts, with its name ("local mapping", "loop
  /// closing"), e.g. to lower its priority (the daemon's local_mapping / loop_closing
  /// niceness: the tracking thread keeps the caller's). Threads these start later (global BA)
  /// inherit what the OS passes on (on Linux, the niceness).
  using ThreadStartHook = std::function<void(const std::string& thread)>;

  /// `vocabulary` may be null (no relocalization, reference keyframe tracking by
  /// projection); it must outlive the system. Throws std::invalid_argument for an invalid
  /// camera or config.
  SlamSystem(const TrackingCamera& camera, const SlamSystemConfig& config,
             const BinaryVocabulary* vocabulary, ThreadStartHook on_thread_start = {});
  ~SlamSystem();
  SlamSystem(const SlamSystem&) = delete;
  SlamSystem& operator=(const SlamSystem&) = delete;

  void setKeyframeCallback(KeyframeCallback callback) { on_keyframe_ = std::move(callback); }
  void setPoseCallback(PoseCallback callback) { on_poses_ = std::move(callback); }
  /// Called on the loop closing thread after each loop correction.
  void setLoopCallback(LoopCloser::LoopCallback callback) { on_loop_ = std::move(callback); }

  /// Tracks a rectified stereo pair. Throws std::invalid_argument for images whose size is
  /// not the camera's. `T_C_G_initial`: pose of the first keyframe (identity when absent).
  TrackingResult trackStereo(uint64_t frame_id, int64_t timestamp_ns, const GrayImage& left,
                             const GrayImage& right,
                             const std::optional<Transformationd>& T_C_G_initial = std::nullopt);
  /// Tracks a grey image with a registered depth image (metres).
  TrackingResult trackRgbd(uint64_t frame_id, int64_t timestamp_ns, const GrayImage& gray,
                           const DepthImage& depth,
                           const std::optional<Transformationd>& T_C_G_initial = std::nullopt);

  /// A copy of the map as it is now (features shared, not copied), for a checkpoint.
  /// Thread-safe (takes the map's shared lock).
  SparseMapSnapshot snapshot() const;
  /// Continues a saved map: before the first frame, replaces the (empty) map by `snapshot`
  /// (SparseMap::restore with the id floors next_keyframe_id / next_landmark_id), rebuilds the
  /// features' grids and BoW vectors and the keyframe database, and leaves the tracker lost,
  /// so the next frames relocalize into the map. Throws std::invalid_argument (map left
  /// empty) when frames were already tracked or the snapshot is inconsistent. Call from the
  /// tracking thread, before trackStereo / trackRgbd.
  void restore(const SparseMapSnapshot& snapshot, KeyframeId next_keyframe_id = 0,
               LandmarkId next_landmark_id = 0);

  /// Waits until local mapping has processed every keyframe handed to it. Thread-safe.
  void waitUntilIdle();
  /// Stops the local mapping thread (after the keyframe in hand). Idempotent.
  void stop();

  const SparseMap& map() const { return map_; }
  LocalMapperStats localMappingStats() const { return local_mapper_.stats(); }
  /// The online disparity correction (LocalMapperConfig::disparity_correction). Thread-safe.
  DisparityCorrectionStats disparityCorrectionStats() const {
    return local_mapper_.disparityCorrectionStats();
  }
  /// Zero when loop closing is off.
  LoopCloserStats loopClosingStats() const {
    return loop_closer_ ? loop_closer_->stats() : LoopCloserStats{};
  }
  size_t databaseSize() const { return database_.size(); }
  const ScalePyramid& pyramid() const { return builder_.pyramid(); }

 private:
  // Announces a keyframe (on_keyframe_) before local mapping gets it, so its pose updates
  // never reach listeners before the keyframe itself.
  class AnnouncingSink : public KeyframeSink {
   public:
    explicit AnnouncingSink(SlamSystem* system) : system_(system) {}
    bool acceptsKeyframes() const override { return system_->local_mapper_.acceptsKeyframes(); }
    size_t queuedKeyframes() const override { return system_->local_mapper_.queuedKeyframes(); }
    void insertKeyframe(Keyframe* keyframe) override;
    void interruptBundleAdjustment() override {
      system_->local_mapper_.interruptBundleAdjustment();
    }

   private:
    SlamSystem* system_;
  };

  TrackingCamera camera_;
  SlamSystemConfig config_;
  const BinaryVocabulary* vocabulary_;
  SparseMap map_;
  KeyframeDatabase database_;
  FrameBuilder builder_;
  LocalMapper local_mapper_;
  AnnouncingSink sink_{this};
  Tracker tracker_;
  std::unique_ptr<LoopCloser> loop_closer_;
  KeyframeCallback on_keyframe_;
  PoseCallback on_poses_;
  LoopCloser::LoopCallback on_loop_;
  std::thread local_mapping_thread_, loop_closing_thread_;
  bool stopped_ = false;
};

}  // namespace cblox
