#include "daemon/mapper/mapper.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include "daemon/common/text_format.h"
#include "daemon/mapper/map_epoch_key.h"
#include "daemon/mapper/output_path.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

// ---------------------------------------------------------------------------------------------
// Names, config, small helpers


std::string MapperReply::value(const std::string& key) const {
  for (const auto& [k, v] : values) {
    if (k == key) return v;
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// The integrator bound to one submap's layer (integrator thread only).

class Mapper::FrameIntegrator {
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

// ---------------------------------------------------------------------------------------------
// Construction, life cycle

namespace {

MapperConfig validated(const MapperConfig& config) {
  if (const std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("MapperConfig: " + e);
  }
  return config;
}

}  // namespace

Mapper::Mapper(const MapperConfig& config, LogSink log)
    : config_(validated(config)),
      log_sink_(std::move(log)),
      output_dir_(std::filesystem::absolute(config_.output_dir).lexically_normal()),
      collection_(SubmapCollectionConfig{config_.layer}),
      poses_(config_.pose_buffer),
      pending_(config_.pending_capacity),
      problem_log_(kNumInputProblems,
                   std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double>(config_.log_interval_s)),
                   [this](const std::string& line) { this->log(line); }),
      policy_(config_.creation),
      integration_ms_(config_.timing_window),
      worker_(&collection_,
              FusionExportWorkerConfig{MapExportConfig{config_.layer, config_.fusion, config_.mesh},
                                       output_dir_, config_.command_queue_capacity,
                                       config_.worker_niceness, config_.worker_sched_idle},
              [this](const FusionPair& pair, bool fused) {
                maintenance_.onFusionResult(pair, fused);
              },
              [this](const std::string& line) { this->log(line); }),
      maintenance_(
          MapMaintenanceConfig{config_.maintenance, config_.maintenance_queue_capacity,
                               config_.maintenance_clock, config_.restart_after_backwards_s},
          &collection_, &policy_, &policy_mutex_, &worker_,
          [this](InputProblem problem, const std::string& message, uint64_t n) {
            count(problem, message, n);
          },
          [this](const std::string& line) { this->log(line); }) {}

void Mapper::setCovarianceRequester(CovarianceRequester requester) {
  maintenance_.setCovarianceRequester(std::move(requester));
}

Mapper::~Mapper() { stop(); }

bool Mapper::start(std::string* error) {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  if (started_) return true;
  std::error_code ec;
  std::filesystem::create_directories(output_dir_, ec);
  if (ec || !std::filesystem::is_directory(output_dir_)) {
    if (error != nullptr) {
      *error = "cannot create output directory " + output_dir_.string() + ": " + ec.message();
    }
    return false;
  }
  started_ = true;
  integrator_thread_ = std::thread([this] { integratorLoop(); });
  maintenance_.start();
  worker_.start();
  return true;
}

void Mapper::stop() {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  if (!started_ || stopped_) return;
  stopped_ = true;
  stop_ = true;
  worker_.stop();  // the export in hand finishes; queued ones are answered "mapper stopping"
  pending_.notify();
  // The integrator first: in ground-truth mode it may wait for maintenance to apply a
  // keyframe. Maintenance then applies what is still queued, so the map's frames are final.
  integrator_thread_.join();
  maintenance_.stop();
}

void Mapper::log(const std::string& line) const {
  if (log_sink_) {
    log_sink_(line);
  } else {
    std::fprintf(stderr, "cblox-mapper: %s\n", line.c_str());
  }
}

void Mapper::count(InputProblem problem, const std::string& message, uint64_t n) {
  if (n == 0) return;
  problems_[static_cast<size_t>(problem)].fetch_add(n, std::memory_order_relaxed);
  problem_log_.report(static_cast<size_t>(problem),
                      std::string("rejected (") + inputProblemName(problem) + "): " + message);
}

void Mapper::reportProblem(InputProblem problem, const std::string& detail) {
  if (problem == InputProblem::kCount) return;
  if (isFrameProblem(problem)) frames_received_.fetch_add(1, std::memory_order_relaxed);
  count(problem, detail);
}

// ---------------------------------------------------------------------------------------------
// Inputs (any thread)

bool Mapper::isRestart(int64_t newest_utime, int64_t utime) const {
  return isTimeRestart(newest_utime, utime, config_.restart_after_backwards_s);
}

bool Mapper::onDepthFrame(DepthFrame frame) {
  frames_received_.fetch_add(1, std::memory_order_relaxed);
  const std::string what = "depth frame " + std::to_string(frame.frame_id);
  if (const std::string e = validate(frame.intrinsics); !e.empty()) {
    count(InputProblem::kDepthInvalid, what + ": bad intrinsics: " + e);
    return false;
  }
  if (frame.depth.width != frame.intrinsics.width ||
      frame.depth.height != frame.intrinsics.height ||
      frame.depth.data.size() !=
          static_cast<size_t>(frame.depth.width) * static_cast<size_t>(frame.depth.height)) {
    count(InputProblem::kDepthInvalid, what + ": depth image " + std::to_string(frame.depth.width) +
                                           "x" + std::to_string(frame.depth.height) +
                                           " does not match its calibration " +
                                           std::to_string(frame.intrinsics.width) + "x" +
                                           std::to_string(frame.intrinsics.height));
    return false;
  }
  if (!frame.color.empty() &&
      (!frame.color.sameSize(frame.depth) || frame.color.data.size() != frame.depth.data.size())) {
    count(InputProblem::kDepthInvalid, what + ": colour image size differs from the depth image");
    return false;
  }
  if (!isFinitePose(frame.T_B_D)) {
    count(InputProblem::kDepthInvalid, what + ": non-finite depth camera extrinsics");
    return false;
  }
  if (!std::isfinite(frame.min_depth_m) || frame.min_depth_m < 0.0f) frame.min_depth_m = 0.0f;
  if (!std::isfinite(frame.max_depth_m) || frame.max_depth_m <= frame.min_depth_m) {
    frame.max_depth_m = 1e9f;  // unknown: no upper limit from the sensor
  }
  {
    std::lock_guard<std::mutex> lock(depth_order_mutex_);
    if (isRestart(last_depth_utime_, frame.utime)) {
      source_restarts_.fetch_add(1, std::memory_order_relaxed);
      log(what + ": depth time stamps went back by " +
          fixed(static_cast<double>(last_depth_utime_ - frame.utime) * 1e-6, 3) +
          " s: source restarted, frame order starts afresh, pose buffer cleared");
      last_depth_utime_ = INT64_MIN;
      // The old stream's poses must not serve the new stream's frames (same time stamps).
      std::lock_guard<std::mutex> pose_lock(pose_order_mutex_);
      poses_.clear();
    }
    if (frame.utime <= last_depth_utime_) {
      count(InputProblem::kDepthOutOfOrder, what + ": time stamp " + std::to_string(frame.utime) +
                                                " us not after the previous " +
                                                std::to_string(last_depth_utime_) + " us");
      return false;
    }
    last_depth_utime_ = frame.utime;
  }
  maintenance_.advanceInputClock(frame.utime);
  pending_.push(PendingFrame{std::move(frame), Clock::now()});
  return true;
}

bool Mapper::onFramePose(const TimedPose& pose) {
  poses_received_.fetch_add(1, std::memory_order_relaxed);
  TimedPose stored = pose;
  // A LOST / NOT_INITIALIZED pose is meaningless; keep it (it stops interpolation across the
  // lost period) even when the tracker filled it with garbage.
  if (!stored.tracking_ok && !isFinitePose(stored.T_G_C)) stored.T_G_C = Transformationd();
  const std::string what = "pose at " + std::to_string(pose.utime) + " us";
  PoseBuffer::AddResult result;
  {
    std::lock_guard<std::mutex> lock(pose_order_mutex_);
    result = poses_.add(stored);
    const int64_t newest = poses_.newestUtime();
    if (result == PoseBuffer::AddResult::kOutOfOrder && isRestart(newest, pose.utime)) {
      source_restarts_.fetch_add(1, std::memory_order_relaxed);
      log(what + ": pose time stamps went back by " +
          fixed(static_cast<double>(newest - pose.utime) * 1e-6, 3) +
          " s: source restarted, pose buffer cleared");
      poses_.clear();
      result = poses_.add(stored);
    }
  }
  switch (result) {
    case PoseBuffer::AddResult::kAdded:
      maintenance_.advanceInputClock(pose.utime);
      pending_.notify();
      return true;
    case PoseBuffer::AddResult::kDuplicate:
      count(InputProblem::kPoseDuplicate, what + ": duplicated time stamp");
      return false;
    case PoseBuffer::AddResult::kOutOfOrder:
      count(InputProblem::kPoseOutOfOrder, what + ": older than the newest pose (" +
                                               std::to_string(poses_.newestUtime()) + " us)");
      return false;
    case PoseBuffer::AddResult::kInvalid:
      count(InputProblem::kPoseInvalid, what + ": non-finite or non-unit rotation");
      return false;
  }
  return false;
}

bool Mapper::onKeyframe(KeyframeId id, int64_t utime, const Transformationd& T_G_K,
                        std::vector<uint64_t> landmark_ids) {
  if (!isFinitePose(T_G_K)) {
    count(InputProblem::kKeyframeInvalid, "keyframe " + std::to_string(id) + ": non-finite pose");
    return false;
  }
  maintenance_.enqueueKeyframe(id, utime, T_G_K, std::move(landmark_ids));
  return true;
}

void Mapper::onKeyframePoses(std::vector<std::pair<KeyframeId, Transformationd>> T_G_K) {
  maintenance_.enqueueBatch(std::move(T_G_K));
}

void Mapper::onCovarianceReply(int64_t request_id, std::vector<FusionCovarianceAnswer> answers) {
  maintenance_.enqueueReply(request_id, std::move(answers));
}


void Mapper::onCommand(const MapperCommand& command, ReplyCallback reply) {
  auto fail = [&](const std::string& message) {
    count(InputProblem::kCommandInvalid, "command '" + command.name + "': " + message);
    MapperReply r;
    r.id = command.id;
    r.ok = false;
    r.message = message;
    if (reply) reply(r);
  };
  if (command.name == "status") {
    if (reply) reply(statusReply(command));
    return;
  }
  if (command.name != "export_mesh" && command.name != "export_submap_meshes") {
    fail("unknown command (known: status, export_mesh, export_submap_meshes)");
    return;
  }
  const auto path = command.args.find("path");
  if (path == command.args.end()) {
    fail("missing argument 'path'");
    return;
  }
  std::string error;
  if (!resolveOutputPath(output_dir_, path->second, &error)) {
    fail(error);
    return;
  }
  worker_.submitExport(command, std::move(reply));
}

// ---------------------------------------------------------------------------------------------
// Integrator thread

void Mapper::integratorLoop() {
  const auto max_wait = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(config_.max_pose_wait_s));
  while (!stop_) {
    pending_.waitForWork(std::chrono::milliseconds(20));  // also ages frames without a pose
    while (!stop_) {
      integrator_busy_ = true;
      Transformationd T_G_B;
      bool jump = false;
      const Clock::time_point now = Clock::now();
      // One view of the poses for the whole scan (lock order: poses, then the in-tray),
      // released before the frame is integrated.
      std::optional<PendingFrame> frame;
      {
        const PoseBuffer::Reader poses(poses_);
        frame = pending_.takeNewestReady([&](const PendingFrame& p) -> FrameReadiness {
          Transformationd T;
          bool j = false;
          const PoseBuffer::Lookup result = poses.lookup(p.frame.utime, &T, &j);
          auto what = [&p] {
            return "depth frame " + std::to_string(p.frame.frame_id) + " at " +
                   std::to_string(p.frame.utime) + " us: ";
          };
          switch (result) {
            case PoseBuffer::Lookup::kFound:
              T_G_B = T;
              jump = j;
              return FrameReadiness::kReady;
            case PoseBuffer::Lookup::kNotYet:
              if (now - p.received <= max_wait) return FrameReadiness::kWait;
              count(InputProblem::kNoPose,
                    what() + "no pose within " + fixed(config_.max_pose_wait_s, 2) + " s");
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kTooOld:
              count(InputProblem::kPoseTooOld, what() + PoseBuffer::name(result));
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kGap:
              count(InputProblem::kPoseGap, what() + PoseBuffer::name(result));
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kAcrossJump:
              count(InputProblem::kAcrossJump, what() + PoseBuffer::name(result));
              return FrameReadiness::kReject;
            case PoseBuffer::Lookup::kLost:
              count(InputProblem::kTrackingLost, what() + PoseBuffer::name(result));
              return FrameReadiness::kReject;
          }
          return FrameReadiness::kReject;
        });
      }
      if (!frame) {
        integrator_busy_ = false;
        break;
      }
      try {
        processFrame(std::move(*frame), T_G_B, jump);
      } catch (const std::exception& e) {
        count(InputProblem::kIntegrationFailed, e.what());
      }
      integrator_busy_ = false;
    }
  }
}

void Mapper::processFrame(PendingFrame pending, const Transformationd& T_G_B, bool jump) {
  DepthFrame& frame = pending.frame;
  const std::string what = "depth frame " + std::to_string(frame.frame_id) + ": ";

  // Ground-truth mode: this frame becomes a keyframe when there is no submap to integrate
  // into yet, or after keyframe_every_n_frames integrated frames.
  if (config_.pose_source == PoseSource::kGroundTruth &&
      (collection_.activeSubmap() == nullptr ||
       frames_since_keyframe_ >= config_.keyframe_every_n_frames)) {
    // Made by map maintenance (its thread applies keyframes); the frame waits for it.
    if (!maintenance_.applySynthesisedKeyframe(frame.frame_id, frame.utime, T_G_B)) return;
    frames_since_keyframe_ = 0;
  }

  // Sensor range: readings outside [min_depth_m, max_depth_m] are no measurement.
  if (frame.min_depth_m > 0.0f || frame.max_depth_m < 1e9f) {
    for (float& d : frame.depth.data) {
      if (!(d >= frame.min_depth_m && d <= frame.max_depth_m)) d = 0.0f;
    }
  }
  const PinholeCamera camera(frame.intrinsics);
  const ColorImage* color = frame.color.empty() ? nullptr : &frame.color;
  const Transformationd T_G_D = T_G_B * frame.T_B_D;

  for (int attempt = 0; attempt < 3; ++attempt) {
    std::shared_ptr<Submap> active;
    SubmapCreationPolicy::FrameAction action;
    {
      std::lock_guard<std::mutex> lock(policy_mutex_);
      active = collection_.activeSubmap();
      // A jump at this frame is already answered when the active subvolume is anchored at a
      // keyframe no older than the frame (the keyframe of the jump arrived first).
      const bool answered = active && active->creationTimeNs() >= frame.utime * 1000;
      action = policy_.onFramePose(active.get(), jump && !answered && attempt == 0);
    }
    if (action == SubmapCreationPolicy::FrameAction::kWaitForAnchor) {
      count(InputProblem::kWaitingForAnchor,
            what + (jump ? "tracking jump: waiting for the next keyframe to anchor a subvolume"
                         : "no subvolume yet: waiting for the first keyframe"));
      return;
    }
    const Clock::time_point start = Clock::now();
    Submap::WriteLock lock = active->lockForIntegration();
    if (!lock) continue;  // finished meanwhile by a new keyframe: integrate into the new one
    if (!frame_integrator_ || frame_integrator_->submapId() != active->id()) {
      frame_integrator_ = std::make_unique<FrameIntegrator>(active->id(), config_.integrator_type,
                                                            config_.integrator, &lock.layer());
    }
    const IntegrationStats stats =
        frame_integrator_->integrate(active->T_M_C(T_G_D), frame.depth, camera, color);
    lock.unlock();
    integration_ms_.add(secondsSince(start) * 1e3);
    frames_integrated_.fetch_add(1, std::memory_order_relaxed);
    if (stats.budget_exhausted) frames_cut_by_budget_.fetch_add(1, std::memory_order_relaxed);
    ++frames_since_keyframe_;
    return;
  }
  count(InputProblem::kIntegrationFailed, what + "the active subvolume kept changing");
}


// ---------------------------------------------------------------------------------------------
// Keyframes and pose batches (maintenance thread; integrator thread for synthesised keyframes)





// ---------------------------------------------------------------------------------------------
// Map maintenance (maintenance thread decides, worker fuses)






// ---------------------------------------------------------------------------------------------
// Fusion / export worker






// ---------------------------------------------------------------------------------------------
// Status

MapperStatus Mapper::status() const {
  MapperStatus s;
  s.num_submaps = collection_.size();
  const std::shared_ptr<Submap> active = collection_.activeSubmap();
  s.active_submap_id = active ? active->id() : -1;
  s.num_blocks = collection_.numBlocks();
  s.memory_bytes = collection_.memoryBytes();
  s.frames_received = frames_received_.load();
  s.frames_integrated = frames_integrated_.load();
  s.frames_cut_by_budget = frames_cut_by_budget_.load();
  const InTrayCounters pending = pending_.counters();
  s.frames_dropped = pending.dropped;
  s.frames_pending = pending_.size();
  s.poses_received = poses_received_.load();
  s.keyframes_applied = maintenance_.keyframesApplied();
  s.keyframe_batches = maintenance_.keyframeBatches();
  s.submaps_moved = maintenance_.submapsMoved();
  s.source_restarts = source_restarts_.load();
  s.exports_done = worker_.exportsDone();
  s.exports_failed = worker_.exportsFailed();
  s.fusion = maintenance_.schedulerStats();
  for (size_t i = 0; i < kNumInputProblems; ++i) {
    s.problems[i] = problems_[i].load(std::memory_order_relaxed);
    if (isFrameProblem(static_cast<InputProblem>(i))) s.frames_rejected += s.problems[i];
  }
  s.integration_ms_last = static_cast<float>(integration_ms_.last());
  s.integration_ms_median = static_cast<float>(integration_ms_.quantile(0.5));
  s.integration_ms_p99 = static_cast<float>(integration_ms_.quantile(0.99));
  return s;
}

std::vector<CovisibilityCandidate> Mapper::covisibilityEdges() const {
  return maintenance_.covisibilityEdges();
}

MapperReply Mapper::statusReply(const MapperCommand& command) const {
  const MapperStatus s = status();
  MapperReply reply;
  reply.id = command.id;
  reply.ok = true;
  reply.message = std::to_string(s.num_submaps) + " subvolumes, " + std::to_string(s.num_blocks) +
                  " blocks, " + std::to_string(s.frames_integrated) + " frames integrated, " +
                  std::to_string(s.frames_dropped) + " dropped, " +
                  std::to_string(s.frames_rejected) + " rejected";
  reply.values = {{"pose_source", poseSourceName(config_.pose_source)},
                  {"output_dir", output_dir_.string()},
                  {"subvolumes", std::to_string(s.num_submaps)},
                  {"active_subvolume", std::to_string(s.active_submap_id)},
                  {"blocks", std::to_string(s.num_blocks)},
                  {"memory_bytes", std::to_string(s.memory_bytes)},
                  {"frames_received", std::to_string(s.frames_received)},
                  {"frames_integrated", std::to_string(s.frames_integrated)},
                  {"frames_cut_by_budget", std::to_string(s.frames_cut_by_budget)},
                  {"frames_dropped", std::to_string(s.frames_dropped)},
                  {"frames_rejected", std::to_string(s.frames_rejected)},
                  {"keyframes", std::to_string(s.keyframes_applied)},
                  {"pose_batches", std::to_string(s.keyframe_batches)},
                  {"source_restarts", std::to_string(s.source_restarts)},
                  {"fusion_candidates", std::to_string(s.fusion.candidates)},
                  {"covariance_requested", std::to_string(s.fusion.requested)},
                  {"subvolumes_fused", std::to_string(s.fusion.fused)},
                  {"rejected_by_q", std::to_string(s.fusion.rejected_by_q)},
                  {"covariance_errors", std::to_string(s.fusion.covariance_errors)},
                  {"integration_ms_median", fixed(s.integration_ms_median, 2)},
                  {"integration_ms_p99", fixed(s.integration_ms_p99, 2)}};
  for (size_t i = 0; i < kNumInputProblems; ++i) {
    if (s.problems[i] > 0) {
      reply.values.emplace_back(
          std::string("rejected_") + inputProblemName(static_cast<InputProblem>(i)),
          std::to_string(s.problems[i]));
    }
  }
  return reply;
}

bool Mapper::waitUntilIdle(std::chrono::milliseconds timeout) const {
  const Clock::time_point deadline = Clock::now() + timeout;
  while (true) {
    // Maintenance before the worker: it hands fusions to the worker while busy.
    const bool idle = pending_.size() == 0 && !integrator_busy_.load() && maintenance_.idle() &&
                      worker_.idle();
    // Re-check the in-tray: a frame may have been taken between the two looks.
    if (idle && pending_.size() == 0 && !integrator_busy_.load()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

}  // namespace cblox
