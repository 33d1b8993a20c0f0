#pragma once

// The planning map served to planners in other processes: distance requests answered on a
// thread of their own, and a dense grid around the vehicle at a fixed rate. Transport-free:
// replies and grids go to sinks (cblox-mapper's LCM adapter publishes them on
// CBLOX_DISTANCE_REPLY and CBLOX_LOCAL_GRID).

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>

#include "core/common/timing_window.h"
#include "core/mapping/planning_config.h"
#include "core/mapping/planning_map.h"

namespace cblox {

/// How a distance request was answered (the values of distance_reply_t's STATUS_*).
enum class DistanceStatus : int8_t {
  kOk = 0,             ///< answered from the request's map epoch (or it asked for any)
  kEpochChanged = 1,   ///< answered, from another map than the request's epoch
  kTooManyPoints = 2,  ///< more than max_points: nothing answered
  kNoPlanningMap = 3,  ///< the mapper keeps no distance field: nothing answered
  kBusy = 4,           ///< the queue was full: nothing answered
};

/// One request's answer. Plain value type.
struct DistanceReply {
  int64_t request_id = 0;
  int64_t map_epoch = 0;  ///< the map that answered
  DistanceStatus status = DistanceStatus::kOk;
  std::string message;    ///< why, when not kOk
  float max_distance_m = 0.0f;
  /// Per requested point when answered (kOk, kEpochChanged), else empty. A point that is
  /// not finite is answered unknown with invalid_point set.
  std::vector<DistanceAnswer> answers;
  std::vector<uint8_t> invalid_point;
};

/// A local grid as the sink receives it.
struct LocalGridSample {
  int64_t utime = 0;       ///< when sampled, us since the Unix epoch
  int64_t map_epoch = 0;
  int64_t pose_utime = 0;  ///< of the vehicle pose the box is centred on
  float max_distance_m = 0.0f;
  LocalGrid grid;
};

/// Counters of a PlanningService, each counted before the reply or grid it counts is handed
/// to its sink. Plain value type.
struct PlanningServiceStats {
  uint64_t requests_answered = 0;  ///< kOk or kEpochChanged
  uint64_t requests_refused = 0;   ///< kTooManyPoints, kNoPlanningMap, kBusy
  uint64_t points_answered = 0;
  uint64_t grids_published = 0;
  uint64_t sink_errors = 0;        ///< a sink threw (caught, counted)
};

/// Answers distance requests and samples local grids on one worker thread, from a
/// PlanningMap (or, without one, refuses with kNoPlanningMap).
///
/// The worker only reads the planning map (its queries sample the fields' published
/// snapshots without a lock), never a subvolume's layer: it cannot block integration. submit() never
/// blocks on the worker either: it bounds the request, copies it into the queue, and
/// returns. Thread-safety: submit() and stats() from any thread; the sinks run on the worker
/// (a refusal's reply on submit()'s caller).
class PlanningService {
 public:
  using ReplySink = std::function<void(const DistanceReply&)>;
  using GridSink = std::function<void(const LocalGridSample&)>;
  /// The map's current epoch (Mapper::mapEpoch()).
  using EpochSource = std::function<int64_t()>;
  /// The vehicle's newest pose (utime, T_G_C), or nullopt before the first.
  using PoseSource = std::function<std::optional<std::pair<int64_t, Transformationd>>()>;

  /// `planning` may be null (the mapper runs without fields) and must outlive the service.
  /// Throws std::invalid_argument with config.validate()'s message when invalid. Starts the
  /// worker.
  PlanningService(const PlanningServiceConfig& config, const PlanningMap* planning,
                  EpochSource epoch, PoseSource pose, ReplySink on_reply, GridSink on_grid);
  /// Stops the worker; requests still queued are dropped unanswered.
  ~PlanningService();
  PlanningService(const PlanningService&) = delete;
  PlanningService& operator=(const PlanningService&) = delete;

  /// Queues request `request_id` for `num_points` points, point(k) giving the k-th (x, y, z
  /// in G). Bounds first: more than max_points is answered kTooManyPoints and a full queue
  /// kBusy, on this thread and before anything is copied; otherwise the points are copied
  /// and the worker answers. `map_epoch` 0 asks for any map; another value that is not the
  /// current epoch gets kEpochChanged with the answers.
  void submit(int64_t request_id, int64_t map_epoch, size_t num_points,
              const std::function<Eigen::Vector3d(size_t)>& point);

  PlanningServiceStats stats() const;
  /// Milliseconds from submit() to the reply sink's return, per answered request.
  const TimingWindow& answerMs() const { return answer_ms_; }

 private:
  struct Request {
    int64_t id = 0;
    int64_t map_epoch = 0;
    std::vector<Eigen::Vector3d> points;
    std::chrono::steady_clock::time_point received;
  };
  void run();
  void answer(const Request& request);
  void sampleGrid();
  void deliver(const DistanceReply& reply);
  DistanceReply refusal(int64_t request_id, DistanceStatus status, std::string message) const;

  const PlanningServiceConfig config_;
  const PlanningMap* const planning_;
  const EpochSource epoch_;
  const PoseSource pose_;
  const ReplySink on_reply_;
  const GridSink on_grid_;
  TimingWindow answer_ms_{200};

  mutable std::mutex mutex_;  // guards queue_, stop_, stats_
  std::condition_variable wake_;
  std::deque<Request> queue_;
  bool stop_ = false;
  PlanningServiceStats stats_;
  std::thread worker_;
};

}  // namespace cblox
