#pragma once

// Frame integration, the mapper's first thread: the newest depth frame whose pose is known
// is integrated into the active subvolume, under the stage of the map's memory cap
// (memory_cap.h) it is in.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/common/in_tray.h"
#include "core/common/timing_window.h"
#include "core/geometry/se3.h"
#include "core/integrator/integrator_config.h"
#include "core/integrator/make_integrator.h"
#include "core/mapping/depth_frame.h"
#include "core/mapping/map_maintenance.h"
#include "core/mapping/mapper_config.h"
#include "core/mapping/mapper_problems.h"
#include "core/mapping/memory_cap.h"
#include "core/mapping/planning_map.h"
#include "core/mapping/pose_buffer.h"
#include "core/mapping/trajectory_log.h"
#include "core/submap/submap_collection.h"
#include "core/submap/submap_creation_policy.h"

namespace cblox {

/// Settings of frame integration (from MapperConfig). Plain value type.
struct FrameIntegrationConfig {
  PoseSource pose_source = PoseSource::kGroundTruth;
  int keyframe_every_n_frames = 10;  ///< ground-truth mode's synthesised keyframes
  IntegratorType integrator_type = IntegratorType::kProjective;
  IntegratorConfig integrator;
  double max_pose_wait_s = 0.5;
  size_t pending_capacity = 4;
  PoseBuffer::Config pose_buffer;
  size_t timing_window = 200;
  MemoryCapConfig memory_cap;
  /// Niceness of the integrator thread, [0, 19] (MapperConfig::integrator_niceness).
  int niceness = 0;
  /// MapperConfig::pending_in_order: frames in order, else the newest ready one wins.
  bool in_order = true;
};

/// What the memory cap did so far (FrameIntegration::memoryCapCounters). Plain value type.
struct MemoryCapCounters {
  MemoryCapState state = MemoryCapState::kOff;  ///< the stage of the last integrated frame
  uint64_t frames_near_only = 0;  ///< integrated with depth cut at near_distance_m (any stage)
  uint64_t frames_at_cap = 0;     ///< of those, integrated at the cap (no new block)
  uint64_t blocks_refused = 0;    ///< blocks allocated at the cap and taken back
};

/// The in-tray of depth frames (newest wins), the frame poses, and the integrator thread:
/// it takes the newest pending frame whose pose the PoseBuffer can give (waiting up to
/// max_pose_wait_s for a pose that is not there yet; frames it can never serve are rejected
/// and counted by reason), applies the creation policy under the shared policy mutex
/// (ground-truth mode: synthesises keyframes, which map maintenance applies while the frame
/// waits) and integrates into the active subvolume under Submap::lockForIntegration() with
/// T_M_D = T_G_M^-1 * T_G_B * T_B_D. Memory cap (memory_cap.h), decided per frame from the
/// map's accounted bytes before it is integrated: from near_only_fraction of the cap on,
/// depth beyond near_distance_m is cut; at the cap, also depth whose point lies in no block of
/// the active subvolume, and every block the frame still allocates there is removed again
/// (existing blocks are still updated), so the map
/// exceeds the cap by at most the blocks of the one frame that crossed it. The map's bytes
/// are the subvolumes' and the planning map's distance fields' (projected: one field block
/// per TSDF block, PlanningMap::projectedBytes, so the fields' refresh lag cannot overrun
/// the cap).
/// Thread-safety: every public member function is thread-safe.
class FrameIntegration {
 public:
  using ProblemSink = std::function<void(InputProblem, const std::string&, uint64_t n)>;

  /// `collection`, `policy`, `policy_mutex` and `maintenance` must outlive it.
  FrameIntegration(FrameIntegrationConfig config, SubmapCollection* collection,
                   SubmapCreationPolicy* policy, std::mutex* policy_mutex,
                   MapMaintenance* maintenance, ProblemSink problems);
  /// Calls stop().
  ~FrameIntegration();
  FrameIntegration(const FrameIntegration&) = delete;
  FrameIntegration& operator=(const FrameIntegration&) = delete;

  /// The planning map whose distance fields count toward the memory cap with the
  /// subvolumes (null: none). It must outlive this; call before start(). Not thread-safe.
  void setPlanningMap(const PlanningMap* planning) { planning_ = planning; }
  /// Starts the thread. Call once.
  void start();
  /// Finishes the frame in hand, joins. Idempotent.
  void stop();

  /// A checked depth frame, into the in-tray (an older waiting one may be dropped, counted).
  void push(DepthFrame frame);
  /// The frame poses (the caller adds them, with its own order and restart rules); call
  /// poseAdded() after each.
  PoseBuffer& poses() { return poses_; }
  const PoseBuffer& poses() const { return poses_; }
  /// The integrated frames' camera positions, per subvolume (thread-safe).
  const TrajectoryLog& trajectory() const { return trajectory_; }
  void poseAdded() { pending_.notify(); }

  /// No frame waiting or in hand.
  bool idle() const;
  uint64_t framesIntegrated() const { return frames_integrated_.load(); }
  uint64_t framesCutByBudget() const { return frames_cut_by_budget_.load(); }
  InTrayCounters pendingCounters() const { return pending_.counters(); }
  size_t pendingFrames() const { return pending_.size(); }
  const TimingWindow& integrationMs() const { return integration_ms_; }
  /// Age of integrated frames when their integration began (received -> start), ms.
  const TimingWindow& frameAgeMs() const { return frame_age_ms_; }
  MemoryCapCounters memoryCapCounters() const;

 private:
  struct PendingFrame {
    DepthFrame frame;
    std::chrono::steady_clock::time_point received;
  };
  class FrameIntegrator;  // one integrator bound to one submap's layer

  void loop();
  // `reference_keyframe`: the frame pose's (PoseBuffer::lookup), -1 for none.
  void processFrame(PendingFrame pending, const Transformationd& T_G_B, bool jump,
                    int64_t reference_keyframe);
  // The frame-driven revisit rule (SubmapCreationPolicy::onFrameReference) for a frame to be
  // integrated into `active`: returns the revisit submap it starts, or `active`. Call with
  // *policy_mutex_ held.
  std::shared_ptr<Submap> applyRevisitRule(std::shared_ptr<Submap> active,
                                           int64_t reference_keyframe, int64_t frame_time_ns);
  // The same for a frame waiting for an anchor after a tracking jump
  // (SubmapCreationPolicy::onJumpReference): the revisit submap it starts, or null when the
  // frame keeps waiting. Call with *policy_mutex_ held.
  std::shared_ptr<Submap> revisitAfterJump(const std::shared_ptr<Submap>& active,
                                           int64_t reference_keyframe, int64_t frame_time_ns);
  // The oldest submap holding `reference_keyframe` (-1: none), unless it belongs to another
  // map epoch than `active`'s (the two maps' frames are unrelated).
  std::optional<SubmapPose> referenceHome(const Submap* active, int64_t reference_keyframe) const;
  // Creates the revisit submap at `home` (its current pose and anchor) and hands it to map
  // maintenance. Call with *policy_mutex_ held.
  std::shared_ptr<Submap> startRevisitSubmap(const SubmapPose& home, int64_t frame_time_ns);

  const FrameIntegrationConfig config_;
  SubmapCollection* const collection_;
  SubmapCreationPolicy* const policy_;
  std::mutex* const policy_mutex_;
  MapMaintenance* const maintenance_;
  const ProblemSink problems_;

  PoseBuffer poses_;
  TrajectoryLog trajectory_;
  InTray<PendingFrame> pending_;
  TimingWindow integration_ms_;
  const PlanningMap* planning_ = nullptr;
  TimingWindow frame_age_ms_;
  // Integrator thread only.
  std::unique_ptr<FrameIntegrator> frame_integrator_;
  int frames_since_keyframe_ = 0;
  NewBlockRefusal refusal_;

  std::atomic<bool> busy_{false}, stop_{false};
  std::atomic<uint64_t> frames_integrated_{0}, frames_cut_by_budget_{0};
  std::atomic<MemoryCapState> cap_state_{MemoryCapState::kOff};
  std::atomic<uint64_t> frames_near_only_{0}, frames_at_cap_{0}, blocks_refused_{0};
  std::mutex lifecycle_mutex_;
  bool started_ = false;
  std::thread thread_;
};

}  // namespace cblox
