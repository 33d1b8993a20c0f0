#include "core/mapping/frame_integration.h"

#include <exception>
#include <optional>
#include <utility>

#include "core/common/text_format.h"
#include "core/common/thread_name.h"
#include "core/common/thread_priority.h"
#include "core/common/utime_ns.h"
#include "core/geometry/pinhole_camera.h"
#include "core/mapping/map_epoch_key.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

// ---------------------------------------------------------------------------------------------
// The integrator bound to one submap's layer (integrator thread only).

class FrameIntegration::FrameIntegrator {
 public:
  FrameIntegrator(SubmapId submap_id, IntegratorType type, const IntegratorConfig& config,
                  TsdfLayer* layer)
      : submap_id_(submap_id), integrator_(makeIntegrator(type, config, layer)) {}

  SubmapId submapId() const { return submap_id_; }

  IntegrationStats integrate(const Transformation& T_M_D, const DepthImage& depth,
                             const PinholeCamera& camera, const ColorImage* color) {
    return integrator_->integrateDepthImage(T_M_D, depth, camera, color);
  }

 private:
  SubmapId submap_id_;
  std::unique_ptr<DepthIntegrator> integrator_;
};

FrameIntegration::FrameIntegration(FrameIntegrationConfig config, SubmapCollection* collection,
                                   SubmapCreationPolicy* policy, std::mutex* policy_mutex,
                                   MapMaintenance* maintenance, ProblemSink problems)
    : config_(std::move(config)),
      collection_(collection),
      policy_(policy),
      policy_mutex_(policy_mutex),
      maintenance_(maintenance),
      problems_(std::move(problems)),
      poses_(config_.pose_buffer),
      pending_(config_.pending_capacity),
      integration_ms_(config_.timing_window),
      frame_age_ms_(config_.timing_window) {}

FrameIntegration::~FrameIntegration() { stop(); }

void FrameIntegration::start() {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  if (started_) return;
  started_ = true;
  thread_ = std::thread([this] {
    nameThisThread("cblox-integrate");
    // Lowering one's own priority needs no privilege: setpriority cannot refuse it.
    if (config_.niceness > 0) lowerThreadPriority(config_.niceness, false);
    loop();
  });
}

void FrameIntegration::stop() {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  stop_ = true;
  pending_.notify();
  if (thread_.joinable()) thread_.join();
}

void FrameIntegration::push(DepthFrame frame) {
  pending_.push(PendingFrame{std::move(frame), Clock::now()});
}

bool FrameIntegration::idle() const { return pending_.size() == 0 && !busy_.load(); }

MemoryCapCounters FrameIntegration::memoryCapCounters() const {
  MemoryCapCounters c;
  c.state = cap_state_.load(std::memory_order_relaxed);
  c.frames_near_only = frames_near_only_.load(std::memory_order_relaxed);
  c.frames_at_cap = frames_at_cap_.load(std::memory_order_relaxed);
  c.blocks_refused = blocks_refused_.load(std::memory_order_relaxed);
  return c;
}

void FrameIntegration::loop() {
  const auto max_wait = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(config_.max_pose_wait_s));
  while (!stop_) {
    pending_.waitForWork(std::chrono::milliseconds(20));  // also ages frames without a pose
    while (!stop_) {
      busy_ = true;
      Transformationd T_G_B;
      bool jump = false;
      int64_t reference = -1;
      const Clock::time_point now = Clock::now();
      // One view of the poses for the whole scan (lock order: poses, then the in-tray),
      // released before the frame is integrated.
      std::optional<PendingFrame> frame;
      {
        const PoseBuffer::Reader poses(poses_);
        const auto readiness = [&](const PendingFrame& p) -> FrameReadiness {
          Transformationd T;
          bool j = false;
          int64_t r = -1;
          const PoseBuffer::Lookup result = poses.lookup(p.frame.utime, &T, &j, &r);
          auto what = [&p] {
            return "depth frame " + std::to_string(p.frame.frame_id) + " at " +
                   std::to_string(p.frame.utime) + " us: ";
          };
          switch (result) {
            case PoseBuffer::Lookup::kFound:
              T_G_B = T;
              jump = j;
              reference = r;
              return FrameReadiness::kReady;
            case PoseBuffer::Lookup::kNotYet:
              if (now - p.received <= max_wait) return FrameReadiness::kWait;
              problems_(InputProblem::kNoPose,
                        what() + "no pose within " + fixed(config_.max_pose_wait_s, 2) + " s", 1);
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kTooOld:
              problems_(InputProblem::kPoseTooOld, what() + PoseBuffer::name(result), 1);
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kGap:
              problems_(InputProblem::kPoseGap, what() + PoseBuffer::name(result), 1);
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kAcrossJump:
              problems_(InputProblem::kAcrossJump, what() + PoseBuffer::name(result), 1);
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kLost:
              problems_(InputProblem::kTrackingLost, what() + PoseBuffer::name(result), 1);
              return FrameReadiness::kReject;
          }
          return FrameReadiness::kReject;
        };
        frame = config_.in_order ? pending_.takeOldestReady(readiness)
                                 : pending_.takeNewestReady(readiness);
      }
      if (!frame) {
        busy_ = false;
        break;
      }
      try {
        processFrame(std::move(*frame), T_G_B, jump, reference);
      } catch (const std::exception& e) {
        problems_(InputProblem::kIntegrationFailed, e.what(), 1);
      }
      busy_ = false;
    }
  }
}

std::optional<SubmapPose> FrameIntegration::referenceHome(const Submap* active,
                                                          int64_t reference_keyframe) const {
  if (reference_keyframe < 0) return std::nullopt;
  std::optional<SubmapPose> home = collection_->oldestSubmapWithKeyframe(reference_keyframe);
  // Another map epoch's subvolume is never a home: the two maps' frames are unrelated.
  if (home && active != nullptr &&
      epochOfKey(home->anchor_keyframe) != epochOfKey(active->anchorKeyframe())) {
    home.reset();
  }
  return home;
}

std::shared_ptr<Submap> FrameIntegration::startRevisitSubmap(const SubmapPose& home,
                                                             int64_t frame_time_ns) {
  // Finishes the previous submap (this thread holds no layer lock: nothing to wait for).
  std::shared_ptr<Submap> revisit =
      collection_->createSubmap(home.T_G_M, home.anchor_keyframe, frame_time_ns);
  maintenance_->adoptRevisitSubmap(revisit->id(), home.id, home.anchor_keyframe,
                                   policy_->lastReason());
  return revisit;
}

std::shared_ptr<Submap> FrameIntegration::applyRevisitRule(std::shared_ptr<Submap> active,
                                                           int64_t reference_keyframe,
                                                           int64_t frame_time_ns) {
  if (policy_->config().revisit_after_frames <= 0 || !active) return active;
  const std::optional<SubmapPose> home = referenceHome(active.get(), reference_keyframe);
  std::optional<SubmapCreationPolicy::ReferenceHome> where;
  if (home) where = SubmapCreationPolicy::ReferenceHome{home->id, home->anchor_keyframe};
  if (!policy_->onFrameReference(*active, where)) return active;
  return startRevisitSubmap(*home, frame_time_ns);
}

std::shared_ptr<Submap> FrameIntegration::revisitAfterJump(const std::shared_ptr<Submap>& active,
                                                           int64_t reference_keyframe,
                                                           int64_t frame_time_ns) {
  if (policy_->config().revisit_after_frames <= 0) return nullptr;
  const std::optional<SubmapPose> home = referenceHome(active.get(), reference_keyframe);
  if (!home) return nullptr;
  if (!policy_->onJumpReference(
          active.get(), SubmapCreationPolicy::ReferenceHome{home->id, home->anchor_keyframe})) {
    return nullptr;
  }
  return startRevisitSubmap(*home, frame_time_ns);
}

void FrameIntegration::processFrame(PendingFrame pending, const Transformationd& T_G_B, bool jump,
                                    int64_t reference_keyframe) {
  DepthFrame& frame = pending.frame;
  const std::string what = "depth frame " + std::to_string(frame.frame_id) + ": ";

  // Ground-truth mode: this frame becomes a keyframe when there is no submap to integrate
  // into yet, or after keyframe_every_n_frames integrated frames.
  if (config_.pose_source == PoseSource::kGroundTruth &&
      (collection_->activeSubmap() == nullptr ||
       frames_since_keyframe_ >= config_.keyframe_every_n_frames)) {
    // Made by map maintenance (its thread applies keyframes); the frame waits for it.
    if (!maintenance_->applySynthesisedKeyframe(frame.frame_id, frame.utime, T_G_B)) return;
    frames_since_keyframe_ = 0;
  }

  // Sensor range: readings outside [min_depth_m, max_depth_m] are no measurement.
  if (frame.min_depth_m > 0.0f || frame.max_depth_m < 1e9f) {
    for (float& d : frame.depth.data) {
      if (!(d >= frame.min_depth_m && d <= frame.max_depth_m)) d = 0.0f;
    }
  }
  // Memory cap: the stage follows the map's bytes as of the last integrated frame.
  const size_t map_bytes =
      collection_->memoryBytes() +
      (planning_ != nullptr
           ? planning_->projectedBytes(collection_->numBlocks(), collection_->config().layer)
           : 0);
  const MemoryCapState cap = memoryCapState(config_.memory_cap, map_bytes);
  const bool near_only = cap == MemoryCapState::kNearOnly || cap == MemoryCapState::kFull;
  if (near_only) cutDepthBeyond(&frame.depth, config_.memory_cap.near_distance_m);
  const PinholeCamera camera(frame.intrinsics);
  const ColorImage* color = frame.color.empty() ? nullptr : &frame.color;
  const Transformationd T_G_D = T_G_B * frame.T_B_D;

  for (int attempt = 0; attempt < 3; ++attempt) {
    std::shared_ptr<Submap> active;
    SubmapCreationPolicy::FrameAction action;
    {
      std::lock_guard<std::mutex> lock(*policy_mutex_);
      active = collection_->activeSubmap();
      const int64_t time_ns = utimeToNs(frame.utime);
      action = policy_->onFramePose(active.get(), jump && attempt == 0, time_ns);
      if (action == SubmapCreationPolicy::FrameAction::kIntegrate && attempt == 0) {
        active = applyRevisitRule(std::move(active), reference_keyframe, time_ns);
      } else if (action == SubmapCreationPolicy::FrameAction::kWaitForAnchor && attempt == 0) {
        if (std::shared_ptr<Submap> revisit =
                revisitAfterJump(active, reference_keyframe, time_ns)) {
          active = std::move(revisit);
          action = SubmapCreationPolicy::FrameAction::kIntegrate;
        }
      }
    }
    if (action == SubmapCreationPolicy::FrameAction::kWaitForAnchor) {
      problems_(InputProblem::kWaitingForAnchor,
                what + (jump ? "tracking jump: waiting for the next keyframe to anchor a subvolume"
                             : "no subvolume yet: waiting for the first keyframe"),
                1);
      return;
    }
    const Clock::time_point start = Clock::now();
    Submap::WriteLock lock = active->lockForIntegration();
    if (!lock) continue;  // finished meanwhile by a new keyframe: integrate into the new one
    if (!frame_integrator_ || frame_integrator_->submapId() != active->id()) {
      frame_integrator_ = std::make_unique<FrameIntegrator>(active->id(), config_.integrator_type,
                                                            config_.integrator, &lock.layer());
    }
    const Transformation T_M_D = active->T_M_C(T_G_D);
    if (cap == MemoryCapState::kFull) {
      cutDepthOutsideBlocks(&frame.depth, frame.intrinsics, T_M_D, lock.layer());
      refusal_.remember(lock.layer());
    }
    const IntegrationStats stats = frame_integrator_->integrate(T_M_D, frame.depth, camera, color);
    trajectory_.add(active->id(), T_M_D.translation().cast<double>());
    const size_t refused =
        cap == MemoryCapState::kFull ? refusal_.removeNewBlocks(&lock.layer()) : 0;
    lock.unlock();  // refreshes the submap's bytes: the next frame's stage sees this one
    integration_ms_.add(secondsSince(start) * 1e3);
    frame_age_ms_.add(std::chrono::duration<double, std::milli>(start - pending.received).count());
    cap_state_.store(cap, std::memory_order_relaxed);
    if (near_only) frames_near_only_.fetch_add(1, std::memory_order_relaxed);
    if (cap == MemoryCapState::kFull) {
      frames_at_cap_.fetch_add(1, std::memory_order_relaxed);
      blocks_refused_.fetch_add(refused, std::memory_order_relaxed);
    }
    frames_integrated_.fetch_add(1, std::memory_order_relaxed);
    if (stats.budget_exhausted) frames_cut_by_budget_.fetch_add(1, std::memory_order_relaxed);
    ++frames_since_keyframe_;
    return;
  }
  problems_(InputProblem::kIntegrationFailed, what + "the active subvolume kept changing", 1);
}

}  // namespace cblox
