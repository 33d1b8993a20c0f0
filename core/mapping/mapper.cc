#include "core/mapping/mapper.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <future>
#include <stdexcept>
#include <system_error>

#include "core/common/utime_ns.h"
#include "core/common/text_format.h"
#include "core/io/text_fields.h"
#include "core/mapping/map_epoch_key.h"
#include "core/mapping/map_persistence.h"
#include "core/mapping/output_path.h"
#include "core/mapping/planning_export.h"
#include "core/persistence/map_store.h"

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
// Construction, life cycle

namespace {

MapperConfig validated(const MapperConfig& config) {
  if (const std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("MapperConfig: " + e);
  }
  return config;
}

// The planning map of `config`, null when it is off.
std::unique_ptr<PlanningMap> makePlanningMap(const MapperConfig& config) {
  if (!config.planning.enabled) return nullptr;
  EsdfConfig esdf = config.planning.esdf;
  esdf.band_blocks = config.planning.bandBlocks(config.integrator.projective_carving_depth_m);
  return std::make_unique<PlanningMap>(esdf);
}

}  // namespace

Mapper::Mapper(const MapperConfig& config, LogSink log)
    : config_(validated(config)),
      log_sink_(std::move(log)),
      output_dir_(std::filesystem::absolute(config_.output_dir).lexically_normal()),
      collection_(SubmapCollectionConfig{config_.layer}),
      problem_log_(kNumInputProblems,
                   std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double>(config_.log_interval_s)),
                   [this](const std::string& line) { this->log(line); }),
      policy_(config_.creation),
      planning_(makePlanningMap(config_)),
      worker_(&collection_,
              FusionExportWorkerConfig{MapExportConfig{config_.layer, config_.fusion, config_.mesh},
                                       output_dir_, config_.command_queue_capacity,
                                       config_.worker_niceness, config_.worker_sched_idle},
              [this](const FusionPair& pair, bool fused) {
                // The worker's thread, owner of the finished layers the fusion changed.
                if (fused && planning_) planning_->refresh(collection_, PlanningMap::Scope::kFinished);
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
          [this](const std::string& line) { this->log(line); }),
      integration_(
          FrameIntegrationConfig{config_.pose_source, config_.keyframe_every_n_frames,
                                 config_.integrator_type, config_.integrator,
                                 config_.max_pose_wait_s, config_.pending_capacity,
                                 config_.pose_buffer, config_.timing_window,
                                 config_.memory_cap, config_.integrator_niceness,
                                 config_.pending_in_order},
          &collection_, &policy_, &policy_mutex_, &maintenance_,
          [this](InputProblem problem, const std::string& message, uint64_t n) {
            count(problem, message, n);
          }) {
  map_epoch_.store(wallUtime(), std::memory_order_release);
  if (planning_) {
    integration_.setPlanningMap(planning_.get());
    maintenance_.setPosesMovedCallback(
        [this] { planning_->setPoses(collection_.poseSnapshot()); });
  }
  if (config_.checkpoint.enabled()) {
    checkpointer_ = std::make_unique<MapCheckpointer>(config_.checkpoint.dir);
    // Test only (scripts/crash_test.sh): a pause before each submap file and the manifest of
    // a checkpoint, so that a kill lands inside a checkpoint write often.
    if (const char* pause = std::getenv("CBLOX_TEST_CHECKPOINT_PAUSE_MS")) {
      checkpointer_->setPauseBeforeEachFile(std::chrono::milliseconds(std::atoi(pause)));
    }
    if (config_.checkpoint.period_s > 0.0) {
      worker_.addPeriodicTask(config_.checkpoint.period_s, [this] { runCheckpoint(); });
    }
  }
  if (planning_) {
    // Finished subvolumes on the worker (it owns their layers); the active one on a thread at
    // the integrator's priority: the worker runs at idle priority and must not hold the
    // layer lock the integrator waits for.
    worker_.addPeriodicTask(config_.planning.refresh_period_s, [this] {
      planning_->refresh(collection_, PlanningMap::Scope::kFinished);
    });
    active_field_ = std::make_unique<ActiveFieldRefresher>(
        planning_.get(), &collection_, config_.planning.refresh_period_s,
        config_.integrator_niceness);
  }
}

void Mapper::setCovarianceRequester(CovarianceRequester requester) {
  maintenance_.setCovarianceRequester(std::move(requester));
}

void Mapper::setMeshStreamSinks(MeshStreamer::UpdateSink on_update,
                                MeshStreamer::SubvolumeSink on_subvolumes) {
  if (!config_.mesh_stream.enabled || mesh_stream_) return;
  mesh_stream_ = std::make_unique<MeshStreamer>(
      config_.mesh_stream, config_.mesh, &collection_, [this] { return mapEpoch(); },
      config_.integrator_niceness, std::move(on_update), std::move(on_subvolumes),
      [this](const std::string& line) { this->log(line); });
  worker_.addPeriodicTask(config_.mesh_stream.period_s, [this] { mesh_stream_->tick(); });
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
  integration_.start();
  maintenance_.start();
  if (mesh_stream_) mesh_stream_->start();
  worker_.start();
  if (active_field_) active_field_->start();
  return true;
}

void Mapper::stop() {
  std::lock_guard<std::mutex> lock(lifecycle_mutex_);
  if (!started_ || stopped_) return;
  stopped_ = true;
  if (active_field_) active_field_->stop();
  worker_.stop();  // the export in hand finishes; queued ones are answered "mapper stopping"
  if (mesh_stream_) mesh_stream_->stop();  // after the worker: its tick may wait for a copy
  // The integrator first: in ground-truth mode it may wait for maintenance to apply a
  // keyframe. Maintenance then applies what is still queued, so the map's frames are final.
  integration_.stop();
  maintenance_.stop();
  // Every thread is stopped: one last checkpoint of the final map, so that a clean stop
  // (SIGTERM from systemd) loses nothing integrated since the last periodic one.
  if (checkpointer_ != nullptr) runCheckpoint();
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
          fixed(secondsBack(last_depth_utime_, frame.utime), 3) +
          " s: source restarted, frame order starts afresh, pose buffer cleared");
      last_depth_utime_ = INT64_MIN;
      // The old stream's poses must not serve the new stream's frames (same time stamps).
      std::lock_guard<std::mutex> pose_lock(pose_order_mutex_);
      integration_.poses().clear();
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
  integration_.push(std::move(frame));
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
    PoseBuffer& poses = integration_.poses();
    result = poses.add(stored);
    const int64_t newest = poses.newestUtime();
    if (result == PoseBuffer::AddResult::kOutOfOrder && isRestart(newest, pose.utime)) {
      source_restarts_.fetch_add(1, std::memory_order_relaxed);
      log(what + ": pose time stamps went back by " +
          fixed(secondsBack(newest, pose.utime), 3) +
          " s: source restarted, pose buffer cleared");
      poses.clear();
      result = poses.add(stored);
    }
  }
  switch (result) {
    case PoseBuffer::AddResult::kAdded:
      maintenance_.advanceInputClock(pose.utime);
      integration_.poseAdded();
      return true;
    case PoseBuffer::AddResult::kDuplicate:
      count(InputProblem::kPoseDuplicate, what + ": duplicated time stamp");
      return false;
    case PoseBuffer::AddResult::kOutOfOrder:
      count(InputProblem::kPoseOutOfOrder, what + ": older than the newest pose (" +
                                               std::to_string(integration_.poses().newestUtime()) + " us)");
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

void Mapper::maintenanceTick() { maintenance_.tick(); }

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
  if (command.name == "mesh_refresh") {
    if (!mesh_stream_) {
      fail("no mesh stream (mesh_stream.enabled is false, or this process does not publish it)");
      return;
    }
    mesh_stream_->requestRefresh();
    MapperReply r;
    r.id = command.id;
    r.ok = true;
    r.message = "the next mesh update period begins a full refresh";
    if (reply) reply(r);
    return;
  }
  const bool planning_export =
      command.name == "export_distance_grid" || command.name == "export_distance_slice";
  if (command.name != "export_mesh" && command.name != "export_submap_meshes" &&
      command.name != "save_map" && command.name != "load_map" && !planning_export) {
    fail("unknown command (known: status, mesh_refresh, export_mesh, export_submap_meshes, save_map, "
         "load_map, export_distance_grid, export_distance_slice)");
    return;
  }
  const auto path = command.args.find("path");
  if (path == command.args.end()) {
    fail("missing argument 'path'");
    return;
  }
  std::string error;
  if (command.name == "load_map") {
    // The operator's map directory: not confined. Checked again on the worker (loadMap).
    if (const size_t n = collection_.size(); n > 0) {
      fail(notEmptyMessage(n));
      return;
    }
    const std::string dir = path->second;
    worker_.submitJob(command, [this, dir] { return loadMap(dir); }, std::move(reply));
    return;
  }
  if (!resolveOutputPath(output_dir_, path->second, &error)) {
    fail(error);
    return;
  }
  if (planning_export) {
    submitPlanningExport(command, &reply, fail);
    return;
  }
  if (command.name == "save_map") {
    // On the worker: no fusion changes finished layers while they are written.
    const std::string dir = path->second;
    worker_.submitJob(
        command,
        [this, dir] {
          return saveMapToOutputDir(collection_, output_dir_, dir, statusCounters(),
                                    [this] { return maintenance_.schedulerState(); });
        },
        std::move(reply));
    return;
  }
  worker_.submitExport(command, std::move(reply));
}

void Mapper::submitPlanningExport(const MapperCommand& command, ReplyCallback* reply,
                                  const std::function<void(const std::string&)>& fail) {
  if (!planning_) {
    fail("the mapper keeps no distance field (planning.enabled is false in its configuration)");
    return;
  }
  // numbers(key, count, what): the argument's numbers, or nullopt after fail().
  const auto numbers = [&](const char* key, size_t count,
                           const char* what) -> std::optional<std::vector<double>> {
    const auto it = command.args.find(key);
    std::string error = "missing";
    std::optional<std::vector<double>> values;
    if (it != command.args.end()) values = parseNumbers(it->second, count, &error);
    if (!values) fail(std::string("argument '") + key + "' (" + what + "): " + error);
    return values;
  };
  // resolution: optional, the voxel size by default.
  double resolution = config_.layer.voxel_size;
  if (command.args.count("resolution") > 0) {
    const std::optional<std::vector<double>> r = numbers("resolution", 1, "metres, > 0");
    if (!r) return;
    if (!((*r)[0] > 0.0)) {
      fail("argument 'resolution': must be > 0");
      return;
    }
    resolution = (*r)[0];
  }
  const std::string path = command.args.at("path");
  if (command.name == "export_distance_grid") {
    const std::optional<std::vector<double>> b = numbers("box", 6, "x0,y0,z0,x1,y1,z1 in metres");
    if (!b) return;
    const Eigen::Vector3d min_G((*b)[0], (*b)[1], (*b)[2]), max_G((*b)[3], (*b)[4], (*b)[5]);
    worker_.submitJob(
        command,
        [this, min_G, max_G, resolution, path] {
          planning_->refresh(collection_, PlanningMap::Scope::kAll);
          return exportDistanceGrid(*planning_, min_G, max_G, resolution, output_dir_, path);
        },
        std::move(*reply));
    return;
  }
  const std::optional<std::vector<double>> zs = numbers("z", 1, "the slice's height in metres");
  if (!zs) return;
  const double z_G = (*zs)[0];
  worker_.submitJob(
      command,
      [this, z_G, resolution, path] {
        planning_->refresh(collection_, PlanningMap::Scope::kAll);
        return exportDistanceSlice(*planning_, z_G, resolution, trajectoryG(), output_dir_, path);
      },
      std::move(*reply));
}

// ---------------------------------------------------------------------------------------------
// Saved maps

std::string Mapper::notEmptyMessage(size_t num_submaps) {
  return "the map is not empty (" + std::to_string(num_submaps) +
         " subvolumes): load a map into a fresh mapper";
}

MapperReply Mapper::loadMap(const std::string& dir) {
  MapperReply reply;
  const Clock::time_point start = Clock::now();
  std::string error;
  // The geometry first, so the refusal names both (loadMap checks it again).
  const std::optional<MapManifest> manifest = readManifest(dir, &error);
  if (!manifest) {
    reply.message = "map not loaded: " + error;
    return reply;
  }
  const LayerConfig& saved = manifest->config.layer;
  if (saved.voxel_size != config_.layer.voxel_size ||
      saved.voxels_per_side != config_.layer.voxels_per_side) {
    reply.message = "map not loaded: " +
                    (std::filesystem::path(dir) / kManifestFileName).string() +
                    ": the map's layer (voxel size " + fixed(saved.voxel_size, 4) + " m, " +
                    std::to_string(saved.voxels_per_side) +
                    " voxels per side) differs from the mapper's (voxel size " +
                    fixed(config_.layer.voxel_size, 4) + " m, " +
                    std::to_string(config_.layer.voxels_per_side) + " voxels per side)";
    return reply;
  }
  MapLoadReport report;
  {
    // Held across the load and the adoption: no keyframe creates or joins a subvolume
    // meanwhile (map maintenance's keyframe path holds it across createSubmap).
    std::lock_guard<std::mutex> lock(policy_mutex_);
    if (const size_t n = collection_.size(); n > 0) {
      reply.message = notEmptyMessage(n);
      return reply;
    }
    if (!cblox::loadMap(dir, &collection_, &report, &error)) {
      reply.message = "map not loaded: " + error;
      return reply;
    }
    maintenance_.adoptLoadedSubmaps(collection_.submaps(), report.maintenance);
    policy_.reset();  // no decision about the loaded active subvolume is pending
    // A map loaded from the checkpoint directory itself (a resume, or --load-map of it): the
    // next checkpoint lists its files again instead of rewriting them. Checkpoints run on the
    // worker, as load_map does, so none is between the manifest read above and this.
    std::error_code ec;
    if (checkpointer_ != nullptr &&
        std::filesystem::equivalent(dir, checkpointer_->dir(), ec) && !ec) {
      checkpointer_->adoptLoaded(*manifest, collection_);
    }
  }
  // A new map: a larger epoch than any before (the clock may stand still or step back).
  map_epoch_.store(std::max(map_epoch_.load() + 1, wallUtime()), std::memory_order_release);
  // The loaded subvolumes' distance fields (on the worker, or before start()).
  if (planning_) planning_->refresh(collection_, PlanningMap::Scope::kAll);
  const double seconds = secondsSince(start);
  reply.ok = true;
  // Not restored: the tracker's map, so a tracker that starts afresh numbers its keyframes
  // from 0 again (a new map epoch keeps them apart).
  reply.message = "loaded " + dir + ": " + std::to_string(report.submaps) + " subvolumes, " +
                  std::to_string(report.blocks) + " blocks, " + std::to_string(report.bytes_read) +
                  " bytes in " + fixed(seconds, 3) + " s (covisibility restored: " +
                  std::to_string(report.maintenance.subvolumes.size()) +
                  " subvolumes with landmarks, " +
                  std::to_string(report.maintenance.backoffs.size()) + " pair back-offs)";
  reply.values = {{"path", dir},
                  {"submaps", std::to_string(report.submaps)},
                  {"blocks", std::to_string(report.blocks)},
                  {"bytes", std::to_string(report.bytes_read)},
                  {"seconds", fixed(seconds, 3)},
                  {"generation", std::to_string(report.generation)}};
  return reply;
}

bool Mapper::syncPlanningMap(std::chrono::milliseconds timeout) {
  if (!planning_) return true;
  {
    std::lock_guard<std::mutex> lock(lifecycle_mutex_);
    if (!started_) {  // no worker: this thread is the only one
      planning_->refresh(collection_, PlanningMap::Scope::kAll);
      return true;
    }
    if (stopped_) return false;
  }
  auto done = std::make_shared<std::promise<bool>>();
  std::future<bool> result = done->get_future();
  MapperCommand command;
  command.name = "sync_planning_map";
  worker_.submitJob(
      command,
      [this] {
        planning_->refresh(collection_, PlanningMap::Scope::kAll);
        MapperReply reply;
        reply.ok = true;
        reply.message = "every distance field follows the map";
        return reply;
      },
      [done](const MapperReply& reply) { done->set_value(reply.ok); });
  return result.wait_for(timeout) == std::future_status::ready && result.get();
}

std::optional<TimedPose> Mapper::newestPose() const { return integration_.poses().newestTracked(); }

std::vector<Eigen::Vector3d> Mapper::trajectoryG() const {
  return integration_.trajectory().positionsG(collection_.poseSnapshot());
}

std::optional<MapperReply> Mapper::resumeFromCheckpoint() {
  const MapperCheckpointConfig& c = config_.checkpoint;
  if (!c.resume || c.dir.empty()) return std::nullopt;
  std::error_code ec;
  const std::filesystem::path manifest = std::filesystem::path(c.dir) / kManifestFileName;
  // No manifest at all: a first run (a checkpoint that never committed leaves none either).
  // Anything else, even an unreadable manifest, goes to loadMap, which names the problem.
  if (!std::filesystem::exists(manifest, ec) && !ec) return std::nullopt;
  MapperReply reply = loadMap(c.dir);
  if (reply.ok) {
    reply.message = "resumed from " + c.dir + " generation " + reply.value("generation") + ": " +
                    reply.value("submaps") + " subvolumes (" + reply.message + ")";
  } else {
    reply.message = "cannot resume from checkpoint.dir " + c.dir + ": " + reply.message;
  }
  return reply;
}

void Mapper::runCheckpoint() {
  std::string error;
  std::optional<MapCheckpointReport> report;
  try {
    report = checkpointer_->checkpoint(
        collection_, statusCounters(), [this] { return maintenance_.schedulerState(); }, &error);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!report) {
    checkpoint_failures_.fetch_add(1, std::memory_order_relaxed);
    if (error != last_checkpoint_error_) {  // once per distinct message
      log("checkpoint into " + checkpointer_->dir() + " failed (the last one stays): " + error);
      last_checkpoint_error_ = error;
    }
    return;
  }
  const bool first = checkpoints_written_.fetch_add(1, std::memory_order_relaxed) == 0;
  last_checkpoint_ms_.store(static_cast<float>(report->milliseconds), std::memory_order_relaxed);
  // checkpoint() returned: the manifest is renamed into place and the directory synced.
  last_checkpoint_utime_.store(wallUtime(), std::memory_order_relaxed);
  checkpoint_generation_.store(report->generation, std::memory_order_release);
  if (first || !last_checkpoint_error_.empty()) {
    log(std::string(first ? "first checkpoint" : "checkpoints written again") + " into " +
        checkpointer_->dir() + ": generation " + std::to_string(report->generation) + ", " +
        std::to_string(report->submaps) + " subvolumes (" +
        std::to_string(report->submaps_written) + " written), " +
        std::to_string(report->bytes_written) + " bytes in " + fixed(report->milliseconds, 1) +
        " ms; then every " + fixed(config_.checkpoint.period_s, 2) + " s");
    last_checkpoint_error_.clear();
  }
}

// ---------------------------------------------------------------------------------------------
// Integrator thread




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
  if (planning_) {
    s.planning = planning_->stats();
    s.memory_bytes += s.planning.memory_bytes;
  }
  if (mesh_stream_) s.mesh_stream = mesh_stream_->stats();
  s.frames_received = frames_received_.load();
  s.frames_integrated = integration_.framesIntegrated();
  s.frames_cut_by_budget = integration_.framesCutByBudget();
  const InTrayCounters pending = integration_.pendingCounters();
  s.frames_dropped = pending.dropped;
  s.frames_pending = integration_.pendingFrames();
  s.poses_received = poses_received_.load();
  s.keyframes_applied = maintenance_.keyframesApplied();
  s.keyframe_batches = maintenance_.keyframeBatches();
  s.submaps_moved = maintenance_.submapsMoved();
  s.source_restarts = source_restarts_.load();
  s.exports_done = worker_.exportsDone();
  s.exports_failed = worker_.exportsFailed();
  s.checkpoints_written = checkpoints_written_.load(std::memory_order_relaxed);
  s.checkpoint_failures = checkpoint_failures_.load(std::memory_order_relaxed);
  s.last_checkpoint_ms = last_checkpoint_ms_.load(std::memory_order_relaxed);
  s.checkpoint_generation = checkpoint_generation_.load(std::memory_order_acquire);
  s.last_checkpoint_utime = last_checkpoint_utime_.load(std::memory_order_relaxed);
  s.fusion = maintenance_.schedulerStats();
  for (size_t i = 0; i < kNumInputProblems; ++i) {
    s.problems[i] = problems_[i].load(std::memory_order_relaxed);
    if (isFrameProblem(static_cast<InputProblem>(i))) s.frames_rejected += s.problems[i];
  }
  const TimingWindow& times = integration_.integrationMs();
  s.integration_ms_last = static_cast<float>(times.last());
  s.integration_ms_median = static_cast<float>(times.quantile(0.5));
  s.integration_ms_p99 = static_cast<float>(times.quantile(0.99));
  const TimingWindow& ages = integration_.frameAgeMs();
  s.frame_age_ms_median = static_cast<float>(ages.quantile(0.5));
  s.frame_age_ms_p99 = static_cast<float>(ages.quantile(0.99));
  if (planning_) {
    s.esdf_ms_median = static_cast<float>(planning_->refreshMs().quantile(0.5));
    s.esdf_ms_p99 = static_cast<float>(planning_->refreshMs().quantile(0.99));
  }
  s.memory_cap_bytes = config_.memory_cap.enabled() ? config_.memory_cap.capBytes() : 0;
  s.memory_cap = integration_.memoryCapCounters();
  return s;
}

std::vector<CovisibilityCandidate> Mapper::covisibilityEdges() const {
  return maintenance_.covisibilityEdges();
}

namespace {

// The counters of a status, in the order "status" replies with them.
std::vector<std::pair<std::string, uint64_t>> integerCounters(const MapperStatus& s) {
  return {{"frames_received", s.frames_received},
          {"frames_integrated", s.frames_integrated},
          {"frames_cut_by_budget", s.frames_cut_by_budget},
          {"frames_dropped", s.frames_dropped},
          {"frames_rejected", s.frames_rejected},
          {"keyframes", s.keyframes_applied},
          {"pose_batches", s.keyframe_batches},
          {"source_restarts", s.source_restarts},
          {"fusion_candidates", s.fusion.candidates},
          {"covariance_requested", s.fusion.requested},
          {"subvolumes_fused", s.fusion.fused},
          {"fused_same_anchor", s.fusion.same_anchor},
          {"rejected_by_q", s.fusion.rejected_by_q},
          {"covariance_errors", s.fusion.covariance_errors},
          {"checkpoints_written", s.checkpoints_written},
          {"checkpoint_failures", s.checkpoint_failures},
          {"frames_near_only", s.memory_cap.frames_near_only},
          {"frames_at_memory_cap", s.memory_cap.frames_at_cap},
          {"blocks_refused", s.memory_cap.blocks_refused}};
}

}  // namespace

std::map<std::string, int64_t> Mapper::statusCounters() const {
  std::map<std::string, int64_t> counters;
  const MapperStatus s = status();
  for (const auto& [name, value] : integerCounters(s)) {
    counters[name] = static_cast<int64_t>(value);
  }
  for (size_t i = 0; i < kNumInputProblems; ++i) {
    counters[std::string("rejected_") + inputProblemName(static_cast<InputProblem>(i))] =
        static_cast<int64_t>(s.problems[i]);
  }
  return counters;
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
                  {"memory_cap_bytes", std::to_string(s.memory_cap_bytes)},
                  {"memory_cap_state", memoryCapStateName(s.memory_cap.state)}};
  for (const auto& [name, value] : integerCounters(s)) {
    reply.values.emplace_back(name, std::to_string(value));
  }
  reply.values.emplace_back("integration_ms_median", fixed(s.integration_ms_median, 2));
  reply.values.emplace_back("integration_ms_p99", fixed(s.integration_ms_p99, 2));
  reply.values.emplace_back("frame_age_ms_median", fixed(s.frame_age_ms_median, 2));
  reply.values.emplace_back("frame_age_ms_p99", fixed(s.frame_age_ms_p99, 2));
  reply.values.emplace_back("esdf_fields", std::to_string(s.planning.fields));
  reply.values.emplace_back("esdf_blocks", std::to_string(s.planning.blocks));
  reply.values.emplace_back("esdf_memory_bytes", std::to_string(s.planning.memory_bytes));
  reply.values.emplace_back("esdf_ms_median", fixed(s.esdf_ms_median, 2));
  reply.values.emplace_back("esdf_ms_p99", fixed(s.esdf_ms_p99, 2));
  reply.values.emplace_back("last_checkpoint_ms", fixed(s.last_checkpoint_ms, 1));
  reply.values.emplace_back("checkpoint_dir", config_.checkpoint.dir);
  reply.values.emplace_back("checkpoint_generation", std::to_string(s.checkpoint_generation));
  reply.values.emplace_back(
      "last_checkpoint_age_s",
      s.last_checkpoint_utime == 0
          ? std::string("-")
          : fixed(static_cast<double>(wallUtime() - s.last_checkpoint_utime) * 1e-6, 1));
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
    const bool idle = integration_.idle() && maintenance_.idle() && worker_.idle();
    // Re-check the in-tray: a frame may have been taken between the two looks.
    if (idle && integration_.idle()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

}  // namespace cblox
