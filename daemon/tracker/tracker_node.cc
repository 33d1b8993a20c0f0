#include "daemon/tracker/tracker_node.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <shared_mutex>
#include <stdexcept>
#include <utility>

#include "core/common/thread_name.h"
#include "core/common/thread_priority.h"
#include "core/common/time_restart.h"
#include "core/common/utime_ns.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

const TrackerNodeConfig& validated(const TrackerNodeConfig& config) {
  if (std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("TrackerNode: " + e);
  }
  return config;
}

std::string describeCamera(const PinholeIntrinsics& K) {
  char text[128];
  std::snprintf(text, sizeof(text), "%dx%d fx %.3f fy %.3f cx %.3f cy %.3f", K.width, K.height,
                K.fx, K.fy, K.cx, K.cy);
  return text;
}

// The same camera for tracking purposes: intrinsics and size, and the stereo baseline.
bool sameCamera(const RectifiedStereoCalibration& a, const RectifiedStereoCalibration& b) {
  constexpr double kPixels = 1e-6, kMetres = 1e-9;
  const PinholeIntrinsics &p = a.intrinsics, &q = b.intrinsics;
  return p.width == q.width && p.height == q.height && std::abs(p.fx - q.fx) <= kPixels &&
         std::abs(p.fy - q.fy) <= kPixels && std::abs(p.cx - q.cx) <= kPixels &&
         std::abs(p.cy - q.cy) <= kPixels && std::abs(a.baseline_m - b.baseline_m) <= kMetres;
}

std::string frameName(const TrackerFrame& frame) {
  return "frame " + std::to_string(frame.frame_id) + " (" + std::to_string(frame.utime) + " us)";
}

}  // namespace

const char* trackerModeName(TrackerMode mode) {
  return mode == TrackerMode::kStereo ? "stereo" : "rgbd";
}

const char* initialPoseName(InitialPose initial_pose) {
  return initial_pose == InitialPose::kIdentity ? "identity" : "ground_truth";
}

SlamSystem::ThreadStartHook slamThreadPriorities(const TrackerNodeConfig& config,
                                                 std::function<void(const std::string&)> log) {
  return [local_mapping = config.local_mapping_niceness,
          loop_closing = config.loop_closing_niceness, log](const std::string& thread) {
    const int niceness = thread == "local mapping" ? local_mapping : loop_closing;
    if (const std::string problem = lowerThreadPriority(niceness, false); !problem.empty()) {
      log(thread + " thread: " + problem);
    }
  };
}

std::string TrackerNodeConfig::validate() const {
  if (std::string e = slam.validate(); !e.empty()) return e;
  for (const auto& [name, niceness] : {std::pair("local_mapping_niceness", local_mapping_niceness),
                                       std::pair("loop_closing_niceness", loop_closing_niceness)}) {
    if (niceness < 0 || niceness > 19) {
      return std::string(name) + " must be in [0, 19], got " + std::to_string(niceness);
    }
  }
  if (calibration) {
    if (std::string e = cblox::validate(calibration->intrinsics); !e.empty()) {
      return "calibration: " + e;
    }
    if (mode == TrackerMode::kStereo &&
        (!(calibration->baseline_m > 0.0) || !std::isfinite(calibration->baseline_m))) {
      return "calibration: baseline_m must be finite and > 0";
    }
  }
  if (!(close_depth_baselines > 0.0) || !std::isfinite(close_depth_baselines)) {
    return "close_depth_baselines must be finite and > 0";
  }
  if (!(rgbd_baseline_m > 0.0) || !std::isfinite(rgbd_baseline_m)) {
    return "rgbd_baseline_m must be finite and > 0";
  }
  if (!(ground_truth_wait_s >= 0.0) || !std::isfinite(ground_truth_wait_s)) {
    return "ground_truth_wait_s must be finite and >= 0";
  }
  if (queue_capacity < 1 || queue_capacity > 16) return "queue_capacity must be in [1, 16]";
  if (!(restart_after_backwards_s >= 0.0) || !std::isfinite(restart_after_backwards_s)) {
    return "restart_after_backwards_s must be finite and >= 0";
  }
  if (std::string e = image_check.validate(); !e.empty()) return "image_check." + e;
  if (timing_window < 1) return "timing_window must be >= 1";
  if (!(log_interval_s > 0.0) || !std::isfinite(log_interval_s)) {
    return "log_interval_s must be finite and > 0";
  }
  if (std::string e = covariance.validate(); !e.empty()) return "covariance." + e;
  if (std::string e = checkpoint.validate(); !e.empty()) return "checkpoint." + e;
  return {};
}

TrackerNode::TrackerNode(const TrackerNodeConfig& config, const BinaryVocabulary* vocabulary,
                         Outputs outputs)
    : config_(validated(config)),
      vocabulary_(vocabulary),
      outputs_(std::move(outputs)),
      queue_(config.queue_capacity),
      problem_log_(kNumTrackerProblems,
                   std::chrono::duration_cast<RateLimitedLog::Clock::duration>(
                       std::chrono::duration<double>(config.log_interval_s)),
                   [this](const std::string& line) { log(line); }),
      tracking_ms_(config.timing_window),
      frame_ms_(config.timing_window) {}

TrackerNode::~TrackerNode() { stop(); }

void TrackerNode::resumeFrom(TrackerResume resume) {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  if (started_) return;
  map_epoch_ = resume.map_epoch;
  log(resume.description);
  resume_ = std::move(resume);
}

void TrackerNode::start() {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  if (started_ || stopped_) return;
  started_ = true;
  if (!config_.checkpoint.dir.empty()) {
    std::optional<IdLease> lease;
    TrackerMapCheckpointer checkpointer(config_.checkpoint.dir);
    if (resume_) {
      lease = IdLease{resume_->map_epoch, resume_->keyframe_floor, resume_->landmark_floor};
      if (resume_->map) checkpointer.adoptLoaded(resume_->index);
    }
    // Test only (scripts/crash_test.sh): a pause before each file of a checkpoint, so that a
    // kill lands inside a checkpoint write often.
    if (const char* pause = std::getenv("CBLOX_TEST_CHECKPOINT_PAUSE_MS")) {
      checkpointer.setPauseBeforeEachFile(std::chrono::milliseconds(std::atoi(pause)));
    }
    id_lease_ = std::make_unique<IdLeaseKeeper>(config_.checkpoint.dir, lease);
    checkpoints_ = std::make_unique<TrackerCheckpointWorker>(
        std::move(checkpointer), config_.checkpoint.period_s, [this] { return mapForCheckpoint(); },
        [this](const std::string& line) { log(line); });
    checkpoints_->start();
  }
  tracking_thread_ = std::thread([this] {
    nameThisThread("cblox-tracking");
    trackingLoop();
  });
}

void TrackerNode::stop() {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  if (stopped_) return;
  stopped_ = true;
  stop_ = true;
  ground_truth_.interrupt();
  queue_.notify();
  if (tracking_thread_.joinable()) tracking_thread_.join();
  SlamSystem* system = nullptr;
  KeyframeCovarianceService* covariance = nullptr;
  {
    std::lock_guard<std::mutex> system_lock(system_mutex_);
    system = system_.get();
    covariance = covariance_.get();
  }
  if (covariance != nullptr) covariance->stop();  // answers the request in hand
  // Kept (not destroyed) so that status() still reads the final map; callbacks may still
  // report the last pose batches while it stops.
  if (system != nullptr) system->stop();
  if (checkpoints_) checkpoints_->stop();  // the last checkpoint, of the settled map
}

std::optional<TrackerMapState> TrackerNode::mapForCheckpoint() const {
  std::lock_guard<std::mutex> lock(system_mutex_);
  if (!system_) return std::nullopt;
  TrackerMapState state;
  state.map = system_->snapshot();
  if (state.map.keyframes.empty()) return std::nullopt;
  state.map_epoch = map_epoch_.load();
  state.camera.intrinsics = tracking_camera_.intrinsics;
  state.camera.baseline_m = tracking_camera_.baseline_m;
  return state;
}

bool TrackerNode::checkpointNow() { return checkpoints_ && checkpoints_->checkpointNow(); }

void TrackerNode::coverIds(const KeyframeInfo& info) {
  if (!id_lease_) return;
  std::string error;
  const uint64_t newest_landmark = info.landmark_ids.empty() ? 0 : info.landmark_ids.back();
  if (!id_lease_->cover(map_epoch_.load(), info.id, newest_landmark, &error)) {
    id_lease_failures_.fetch_add(1, std::memory_order_relaxed);
    log("cannot extend the id lease (ids may repeat after a crash): " + error);
  }
}

namespace {
bool sameCamera(const TrackingCamera& camera, const TrackerMapCamera& saved) {
  const PinholeIntrinsics& a = camera.intrinsics;
  const PinholeIntrinsics& b = saved.intrinsics;
  const auto close = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::abs(y); };
  return a.width == b.width && a.height == b.height && close(a.fx, b.fx) && close(a.fy, b.fy) &&
         close(a.cx, b.cx) && close(a.cy, b.cy) && close(camera.baseline_m, saved.baseline_m);
}
}  // namespace

void TrackerNode::restorePending(SlamSystem* system, const TrackingCamera& camera) {
  std::optional<TrackerResume> resume = std::move(resume_);
  resume_.reset();
  if (!resume || !resume->map) return;
  std::string why;
  if (!sameCamera(camera, resume->map->camera)) {
    why = "its camera (" + describeCamera(resume->map->camera.intrinsics) + ", baseline " +
          std::to_string(resume->map->camera.baseline_m) + " m) is not the one in use";
  } else {
    try {
      system->restore(resume->map->map, resume->keyframe_floor, resume->landmark_floor);
      size_t good = 0;
      for (const KeyframeSnapshot& k : resume->map->map.keyframes) good += k.bad ? 0 : 1;
      resumed_keyframes_ = good;
      map_started_ = true;
      setState("lost: relocalizing in the resumed map");
      log("resumed map restored: " + std::to_string(good) + " keyframes; relocalizing in it");
      return;
    } catch (const std::exception& e) {
      why = e.what();
    }
  }
  map_epoch_ = resume->map_epoch + 1;
  log("the saved map cannot be continued (" + why + "): starting a new map in epoch " +
      std::to_string(map_epoch_.load()));
}

bool TrackerNode::onFrame(TrackerFrame frame) {
  frames_received_.fetch_add(1, std::memory_order_relaxed);
  const std::string what = frameName(frame) + ": ";
  std::lock_guard<std::mutex> lock(input_mutex_);
  if (config_.calibration) {
    frame.calibration = config_.calibration;  // the message's calibration is not used
  } else if (!frame.calibration) {
    count(TrackerProblem::kBadCalibration, what + frame.calibration_error);
    return false;
  }
  const PinholeIntrinsics& K = frame.calibration->intrinsics;
  if (frame.image.width != K.width || frame.image.height != K.height) {
    count(TrackerProblem::kWrongSize, what + "image " + std::to_string(frame.image.width) + "x" +
                                          std::to_string(frame.image.height) +
                                          ", the calibration is " + std::to_string(K.width) + "x" +
                                          std::to_string(K.height));
    return false;
  }
  if (!config_.calibration && camera_ && !sameCamera(*camera_, *frame.calibration)) {
    count(TrackerProblem::kCalibrationChanged,
          what + "calibration " + describeCamera(K) + " baseline " +
              std::to_string(frame.calibration->baseline_m) + " m differs from the one in use, " +
              describeCamera(camera_->intrinsics) + " baseline " +
              std::to_string(camera_->baseline_m) + " m");
    return false;
  }
  if (isTimeRestart(last_utime_, frame.utime, config_.restart_after_backwards_s)) {
    source_restarts_.fetch_add(1, std::memory_order_relaxed);
    log(what + "time went back by " + std::to_string(secondsBack(last_utime_, frame.utime)) +
        " s: the source restarted; a new map starts (map epoch " +
        std::to_string(map_epoch_.load() + 1) + ")");
    frame.starts_new_map = true;
  } else if (frame.utime <= last_utime_) {
    count(TrackerProblem::kOutOfOrder, what + "not after the previous frame " +
                                           std::to_string(last_frame_id_) + " (" +
                                           std::to_string(last_utime_) + " us)");
    return false;
  } else if (frame.frame_id <= last_frame_id_) {
    source_restarts_.fetch_add(1, std::memory_order_relaxed);
    log(what + "frame ids went back (from " + std::to_string(last_frame_id_) +
        ") while time went on: the capture restarted; tracking continues in the same map");
  }
  if (!camera_) camera_ = frame.calibration;
  last_frame_id_ = frame.frame_id;
  last_utime_ = frame.utime;
  queue_.push(std::move(frame));
  return true;
}

void TrackerNode::onGroundTruth(int64_t frame_id, int64_t utime, const Transformationd& T_G_C) {
  if (config_.initial_pose == InitialPose::kGroundTruth) ground_truth_.add(frame_id, utime, T_G_C);
}

void TrackerNode::reportProblem(TrackerProblem problem, const std::string& detail) {
  if (isRejection(problem)) frames_received_.fetch_add(1, std::memory_order_relaxed);
  count(problem, detail);
}

void TrackerNode::count(TrackerProblem problem, const std::string& message) {
  const size_t kind = static_cast<size_t>(problem);
  if (kind < kNumTrackerProblems) problems_[kind].fetch_add(1, std::memory_order_relaxed);
  problem_log_.report(kind, std::string(trackerProblemName(problem)) + ": " + message);
}

void TrackerNode::log(const std::string& line) const {
  if (outputs_.log) {
    outputs_.log(line);
  } else {
    std::fprintf(stderr, "cblox-tracker: %s\n", line.c_str());
  }
}

void TrackerNode::setState(std::string state) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  state_ = std::move(state);
}

void TrackerNode::trackingLoop() {
  if (config_.calibration && resume_) {
    // The camera is known: the saved map is restored now, not on the first frame.
    std::string error;
    if (!ensureSystem(*config_.calibration, &error)) log(error);
  }
  while (!stop_) {
    queue_.waitForWork(std::chrono::milliseconds(100));
    if (stop_) break;
    const auto ready = [this](const TrackerFrame&) {
      // Set under the queue's lock: waitUntilIdle never sees an empty queue and an idle
      // thread while a frame is being handed over.
      busy_ = true;
      return FrameReadiness::kReady;
    };
    std::optional<TrackerFrame> frame =
        config_.catch_up ? queue_.takeOldestReady(ready) : queue_.takeNewestReady(ready);
    if (!frame) continue;
    processFrame(*frame);
    {
      std::lock_guard<std::mutex> lock(idle_mutex_);
      busy_ = false;
    }
    idle_cv_.notify_all();
  }
}

bool TrackerNode::ensureSystem(const RectifiedStereoCalibration& calibration, std::string* error) {
  if (system_) return true;
  const TrackingCamera camera = makeTrackingCamera(
      calibration.intrinsics,
      config_.mode == TrackerMode::kStereo ? calibration.baseline_m : config_.rgbd_baseline_m,
      config_.close_depth_baselines);
  std::unique_ptr<SlamSystem> system;
  try {
    system = std::make_unique<SlamSystem>(
        camera, config_.slam, vocabulary_,
        slamThreadPriorities(config_, [this](const std::string& line) { log(line); }));
  } catch (const std::exception& e) {
    *error = std::string("cannot start the SLAM system: ") + e.what();
    return false;
  }
  system->setKeyframeCallback([this](const KeyframeInfo& info) {
    coverIds(info);  // before the ids leave the process
    keyframes_.fetch_add(1, std::memory_order_relaxed);
    if (outputs_.keyframe) outputs_.keyframe(info);
  });
  system->setPoseCallback([this](const KeyframePoseBatch& batch, PoseUpdateReason reason) {
    if (batch.empty()) return;
    pose_batches_.fetch_add(1, std::memory_order_relaxed);
    if (outputs_.keyframe_poses) outputs_.keyframe_poses(batch, reason);
  });
  system->setLoopCallback([this](const LoopClosureEvent& event) {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "loop closed: keyframe %lld matches keyframe %lld (%d inliers); corrected by "
                  "%.3f m in %.1f ms (essential graph of %d keyframes, %d edges: %.1f ms; "
                  "the map locked %.1f ms)",
                  static_cast<long long>(event.query), static_cast<long long>(event.candidate),
                  event.inliers, event.correction_m, event.correction_ms, event.graph_keyframes,
                  event.graph_edges, event.graph_ms, event.locked_ms);
    log(text);
  });
  log(std::string(trackerModeName(config_.mode)) + " camera " + describeCamera(camera.intrinsics) +
      ", baseline " + std::to_string(camera.baseline_m) + " m" +
      (config_.mode == TrackerMode::kRgbd ? " (virtual)" : "") +
      (vocabulary_ != nullptr ? "" : "; no vocabulary: no relocalization, no loop closing"));
  auto covariance = std::make_unique<KeyframeCovarianceService>(
      system->map(), camera, system->pyramid(), config_.covariance,
      [this](const KeyframeCovarianceReply& reply) {
        if (outputs_.covariance_reply) outputs_.covariance_reply(reply);
      });
  restorePending(system.get(), camera);
  covariance->start();
  std::lock_guard<std::mutex> lock(system_mutex_);
  system_ = std::move(system);
  covariance_ = std::move(covariance);
  tracking_camera_ = camera;
  return true;
}

void TrackerNode::onCovarianceRequest(KeyframeCovarianceRequest request, int32_t map_epoch) {
  std::string why;
  {
    std::lock_guard<std::mutex> lock(system_mutex_);
    if (map_epoch != map_epoch_.load()) {
      why = "keyframes of map epoch " + std::to_string(map_epoch) +
            "; the tracker's map is epoch " + std::to_string(map_epoch_.load());
    } else if (covariance_ && !stop_) {
      covariance_->submit(std::move(request));
      return;
    } else {
      why = stop_ ? "the tracker is stopping" : "the tracker has no map yet";
    }
  }
  KeyframeCovarianceReply reply;
  reply.request_id = request.request_id;
  for (const KeyframePair& pair : request.pairs) reply.results.push_back(failedPair(pair, why));
  if (outputs_.covariance_reply) outputs_.covariance_reply(reply);
}

void TrackerNode::publish(FramePoseReport report) {
  report.map_epoch = map_epoch_.load();
  frames_processed_.fetch_add(1, std::memory_order_relaxed);
  pose_published_ = report.T_G_C.has_value();
  if (outputs_.frame_pose) outputs_.frame_pose(report);
}

void TrackerNode::reportUntracked(const TrackerFrame& frame, TrackerProblem problem,
                                  const std::string& reason) {
  const bool started = map_started_;
  FramePoseReport report;
  report.utime = frame.utime;
  report.frame_id = frame.frame_id;
  report.state = started ? FramePoseState::kLost : FramePoseState::kNotInitialized;
  report.reason = reason;
  (started ? frames_lost_ : frames_not_initialized_).fetch_add(1, std::memory_order_relaxed);
  count(problem, frameName(frame) + ": " + reason);
  setState(std::string(started ? "lost: " : "not initialized: ") + reason);
  publish(report);
}

void TrackerNode::startNewMap(const TrackerFrame& frame) {
  std::unique_ptr<SlamSystem> system;
  std::unique_ptr<KeyframeCovarianceService> covariance;
  {
    std::lock_guard<std::mutex> lock(system_mutex_);
    system = std::move(system_);
    covariance = std::move(covariance_);
  }
  // The covariance service reads the map: it stops first. The SLAM threads finish what they
  // hold (their last pose batches still go out in the old epoch), then the epoch moves on.
  if (covariance) covariance->stop();
  if (system) system->stop();
  covariance.reset();
  system.reset();
  map_epoch_.fetch_add(1);
  map_started_ = false;
  pose_published_ = false;
  map_reset_pending_ = true;
  log(frameName(frame) + ": map epoch " + std::to_string(map_epoch_.load()) + " begins");
}

void TrackerNode::processFrame(TrackerFrame& frame) {
  if (frame.starts_new_map) startNewMap(frame);
  std::string error;
  if (!ensureSystem(*frame.calibration, &error)) {
    reportUntracked(frame, TrackerProblem::kTrackingFailed, error);
    return;
  }
  SlamSystem& system = *system_;  // only this thread replaces it (startNewMap)
  const bool stereo = config_.mode == TrackerMode::kStereo;

  // Nothing to track at all: say so without disturbing the tracker's motion model.
  std::optional<ImageCheckResult> defect =
      checkImage(frame.image, config_.image_check, stereo ? "left image" : "image");
  if (!defect && stereo) defect = checkImage(frame.right, config_.image_check, "right image");
  if (defect) {
    const TrackerProblem problem = defect->defect == ImageDefect::kDark ? TrackerProblem::kDarkImage
                                   : defect->defect == ImageDefect::kSaturated
                                       ? TrackerProblem::kSaturatedImage
                                       : TrackerProblem::kTexturelessImage;
    reportUntracked(frame, problem, defect->description);
    return;
  }

  std::optional<Transformationd> T_C_G_initial;
  if (!map_started_ && config_.initial_pose == InitialPose::kGroundTruth) {
    const auto wait = std::chrono::milliseconds(
        static_cast<int64_t>(std::llround(config_.ground_truth_wait_s * 1000.0)));
    const std::optional<Transformationd> T_G_C =
        ground_truth_.waitFor(frame.frame_id, frame.utime, wait);
    if (!T_G_C) {
      reportUntracked(frame, TrackerProblem::kNoGroundTruth,
                      "no ground-truth pose (CBLOX_GT_POSE) of this frame within " +
                          std::to_string(config_.ground_truth_wait_s) +
                          " s; initial_pose ground_truth needs it to start the map");
      return;
    }
    T_C_G_initial = T_G_C->inverse();
  }

  TrackingResult result;
  const Clock::time_point start = Clock::now();
  try {
    const int64_t timestamp_ns = utimeToNs(frame.utime);
    const uint64_t id = static_cast<uint64_t>(frame.frame_id);
    result = stereo ? system.trackStereo(id, timestamp_ns, frame.image, frame.right, T_C_G_initial)
                    : system.trackRgbd(id, timestamp_ns, frame.image, frame.depth, T_C_G_initial);
  } catch (const std::exception& e) {
    reportUntracked(frame, TrackerProblem::kTrackingFailed, e.what());
    return;
  }
  frame_ms_.add(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  tracking_ms_.add(result.time_ms);
  map_started_ = map_started_ || result.state != TrackingState::kNotInitialized;

  if (result.state == TrackingState::kNotInitialized) {
    reportUntracked(frame, TrackerProblem::kNotInitialized, result.reason);
    return;
  }
  if (result.state != TrackingState::kOk || !result.T_C_G) {
    reportUntracked(frame, TrackerProblem::kTrackingLost,
                    result.reason.empty() ? "tracking lost" : result.reason);
    return;
  }
  FramePoseReport report;
  report.utime = frame.utime;
  report.frame_id = frame.frame_id;
  report.T_G_C = result.T_C_G->inverse();
  report.reference_keyframe_id = result.reference_keyframe;
  if (result.relocalized) {
    report.state = FramePoseState::kRelocalized;
    relocalizations_.fetch_add(1, std::memory_order_relaxed);
  } else if (result.map_corrected) {
    report.state = FramePoseState::kLoopCorrected;
    loop_corrected_frames_.fetch_add(1, std::memory_order_relaxed);
  } else {
    report.state = FramePoseState::kOk;
  }
  if (map_reset_pending_) {
    report.state = FramePoseState::kMapReset;  // the new map's first pose
    map_reset_pending_ = false;
  }
  report.jump = report.state != FramePoseState::kOk || (!pose_published_ && !result.initialized);
  frames_tracked_.fetch_add(1, std::memory_order_relaxed);
  setState("tracking");
  publish(report);
}

TrackerStatus TrackerNode::status() const {
  TrackerStatus s;
  s.frames_received = frames_received_.load();
  s.frames_dropped = queue_.counters().dropped;
  s.frames_processed = frames_processed_.load();
  s.frames_tracked = frames_tracked_.load();
  s.frames_lost = frames_lost_.load();
  s.frames_not_initialized = frames_not_initialized_.load();
  s.relocalizations = relocalizations_.load();
  s.loop_corrected_frames = loop_corrected_frames_.load();
  s.keyframes = keyframes_.load();
  s.pose_batches = pose_batches_.load();
  s.source_restarts = source_restarts_.load();
  if (checkpoints_) {
    const TrackerCheckpointStats c = checkpoints_->stats();
    s.checkpoints_written = c.written;
    s.checkpoint_failures = c.failures;
    s.checkpoint_generation = c.generation;
    s.last_checkpoint_ms = c.last_ms;
  }
  s.id_lease_failures = id_lease_failures_.load();
  s.resumed_keyframes = resumed_keyframes_.load();
  s.map_epoch = map_epoch_.load();
  for (size_t i = 0; i < kNumTrackerProblems; ++i) {
    s.problems[i] = problems_[i].load(std::memory_order_relaxed);
    if (isRejection(static_cast<TrackerProblem>(i))) s.frames_rejected += s.problems[i];
  }
  {
    std::lock_guard<std::mutex> lock(system_mutex_);
    if (system_) {
      {
        std::shared_lock<std::shared_mutex> map_lock(system_->map().mutex());
        s.landmarks = system_->map().numLandmarks();
      }
      const LoopCloserStats loops = system_->loopClosingStats();
      s.loops_closed = loops.loops_closed;
      s.loops_rejected_drift = loops.loops_rejected_drift;
      s.essential_graphs_failed = loops.essential_graphs_failed;
      s.global_bundle_adjustments = loops.global_bundle_adjustments;
      s.global_bundle_adjustments_abandoned = loops.global_bundle_adjustments_abandoned;
      const LocalMapperStats mapping = system_->localMappingStats();
      s.local_bundle_adjustments = mapping.bundle_adjustments;
      s.local_bundle_adjustments_interrupted = mapping.bundle_adjustments_aborted;
      s.local_mapping_cpu_ms = 1e3 * mapping.cpu_s.total();
    }
    if (covariance_) {
      const KeyframeCovarianceServiceStats c = covariance_->stats();
      s.covariance_requests = c.requests;
      s.covariance_pairs_ok = c.pairs_ok;
      s.covariance_pairs_failed = c.pairs_failed;
      s.covariance_linearizations = c.linearizations;
      s.covariance_reused = c.reused;
      s.covariance_build_ms = c.last_build_ms;
      s.covariance_solve_ms = c.last_solve_ms;
    }
  }
  s.tracking_ms_median = tracking_ms_.quantile(0.5);
  s.tracking_ms_p95 = tracking_ms_.quantile(0.95);
  s.frame_ms_median = frame_ms_.quantile(0.5);
  s.frame_ms_p95 = frame_ms_.quantile(0.95);
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    s.state = state_;
  }
  return s;
}

bool TrackerNode::waitUntilSettled(std::chrono::milliseconds timeout) const {
  const Clock::time_point deadline = Clock::now() + timeout;
  {
    std::unique_lock<std::mutex> lock(idle_mutex_);
    // Slices: a frame pushed without a notification of idle_cv_ is seen at the next look.
    while (queue_.size() > 0 || busy_) {
      if (Clock::now() >= deadline) return false;
      idle_cv_.wait_for(lock, std::chrono::milliseconds(20));
    }
  }
  SlamSystem* system = nullptr;
  KeyframeCovarianceService* covariance = nullptr;
  {
    std::lock_guard<std::mutex> lock(system_mutex_);  // created once, kept until destruction
    system = system_.get();
    covariance = covariance_.get();
  }
  if (system != nullptr) system->waitUntilIdle();
  if (covariance != nullptr) covariance->waitUntilIdle();
  return true;
}

bool TrackerNode::waitUntilIdle(std::chrono::milliseconds timeout) const {
  const Clock::time_point deadline = Clock::now() + timeout;
  while (queue_.size() > 0 || busy_) {
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace cblox
