#include "core/mapping/planning_service.h"

#include <cmath>
#include <exception>
#include <stdexcept>
#include <utility>

#include "core/common/utime_ns.h"
#include "core/common/thread_name.h"

namespace cblox {

namespace {

using Clock = std::chrono::steady_clock;

const PlanningServiceConfig& validated(const PlanningServiceConfig& config) {
  if (const std::string e = config.validate(); !e.empty()) throw std::invalid_argument(e);
  return config;
}

}  // namespace

PlanningService::PlanningService(const PlanningServiceConfig& config, const PlanningMap* planning,
                                 EpochSource epoch, PoseSource pose, ReplySink on_reply,
                                 GridSink on_grid)
    : config_(validated(config)),
      planning_(planning),
      epoch_(std::move(epoch)),
      pose_(std::move(pose)),
      on_reply_(std::move(on_reply)),
      on_grid_(std::move(on_grid)) {
  worker_ = std::thread([this] { run(); });
}

PlanningService::~PlanningService() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

DistanceReply PlanningService::refusal(int64_t request_id, DistanceStatus status,
                                       std::string message) const {
  DistanceReply reply;
  reply.request_id = request_id;
  reply.map_epoch = epoch_();
  reply.status = status;
  reply.message = std::move(message);
  reply.max_distance_m = planning_ != nullptr ? planning_->config().max_distance_m : 0.0f;
  return reply;
}

void PlanningService::submit(int64_t request_id, int64_t map_epoch, size_t num_points,
                             const std::function<Eigen::Vector3d(size_t)>& point) {
  if (num_points > config_.max_points) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.requests_refused;
    }
    deliver(refusal(request_id, DistanceStatus::kTooManyPoints,
                    std::to_string(num_points) + " points, more than the " +
                        std::to_string(config_.max_points) + " one request may carry"));
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() < config_.queue_capacity) {
      Request request;
      request.id = request_id;
      request.map_epoch = map_epoch;
      request.received = Clock::now();
      request.points.reserve(num_points);
      for (size_t k = 0; k < num_points; ++k) request.points.push_back(point(k));
      queue_.push_back(std::move(request));
      wake_.notify_one();
      return;
    }
    ++stats_.requests_refused;
  }
  deliver(refusal(request_id, DistanceStatus::kBusy,
                  std::to_string(config_.queue_capacity) +
                      " requests already wait for an answer: ask again"));
}

PlanningServiceStats PlanningService::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void PlanningService::deliver(const DistanceReply& reply) {
  try {
    on_reply_(reply);
  } catch (const std::exception&) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.sink_errors;
  }
}

void PlanningService::run() {
  nameThisThread("cblox-planning");
  const bool grids = config_.grid_period_s > 0.0 && on_grid_ != nullptr && planning_ != nullptr;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.grid_period_s));
  Clock::time_point next_grid = Clock::now() + period;
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    if (!queue_.empty()) {
      Request request = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      answer(request);
      lock.lock();
      continue;
    }
    if (grids && Clock::now() >= next_grid) {
      lock.unlock();
      sampleGrid();
      lock.lock();
      // The next one a period after this one was due, or after now when it ran late.
      next_grid = std::max(next_grid + period, Clock::now());
      continue;
    }
    if (grids) {
      wake_.wait_until(lock, next_grid);
    } else {
      wake_.wait(lock);
    }
  }
}

void PlanningService::answer(const Request& request) {
  if (planning_ == nullptr) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.requests_refused;
    }
    deliver(refusal(request.id, DistanceStatus::kNoPlanningMap,
                    "the mapper keeps no distance field (planning.enabled is false in its "
                    "configuration)"));
    return;
  }
  DistanceReply reply;
  reply.request_id = request.id;
  reply.map_epoch = epoch_();
  reply.max_distance_m = planning_->config().max_distance_m;
  if (request.map_epoch != 0 && request.map_epoch != reply.map_epoch) {
    reply.status = DistanceStatus::kEpochChanged;
    reply.message = "map epoch " + std::to_string(request.map_epoch) +
                    " is not the mapper's: answered from map epoch " +
                    std::to_string(reply.map_epoch);
  }
  // Non-finite points are answered invalid; the rest in one batch (one pose snapshot).
  reply.invalid_point.assign(request.points.size(), 0);
  std::vector<Eigen::Vector3d> valid;
  valid.reserve(request.points.size());
  for (size_t k = 0; k < request.points.size(); ++k) {
    if (request.points[k].allFinite()) {
      valid.push_back(request.points[k]);
    } else {
      reply.invalid_point[k] = 1;
    }
  }
  std::vector<DistanceAnswer> answers;
  planning_->queryBatch(valid, &answers, config_.query_threads);
  reply.answers.resize(request.points.size());
  for (size_t k = 0, v = 0; k < request.points.size(); ++k) {
    if (!reply.invalid_point[k]) reply.answers[k] = answers[v++];
  }
  {
    // Counted before the reply leaves: whoever got it sees it counted.
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.requests_answered;
    stats_.points_answered += request.points.size();
  }
  deliver(reply);
  answer_ms_.add(std::chrono::duration<double, std::milli>(Clock::now() - request.received).count());
}

void PlanningService::sampleGrid() {
  const std::optional<std::pair<int64_t, Transformationd>> pose = pose_();
  if (!pose) return;
  const Eigen::Vector3d centre = pose->second.translation();
  if (!centre.allFinite()) return;
  // The box's corner on the grid of `resolution` through G's origin, so that consecutive
  // grids share their cells.
  const double r = config_.grid_resolution_m;
  const Eigen::Vector3d min_G = ((centre - 0.5 * config_.grid_size_m) / r).array().floor() * r;
  const Eigen::Vector3d cells = (config_.grid_size_m / r).array().ceil();
  // Half a cell short of the last cell's far side: the cell count cannot round up by one.
  const Eigen::Vector3d max_G = min_G + (cells.array() - 0.5).matrix() * r;
  LocalGridSample sample;
  std::string error;
  // Refused only for a box far from the origin (the bounds' rounding); nothing to send.
  if (!planning_->localGrid(min_G, max_G, r, &sample.grid, &error)) return;
  sample.utime = wallUtime();
  sample.map_epoch = epoch_();
  sample.pose_utime = pose->first;
  sample.max_distance_m = planning_->config().max_distance_m;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.grids_published;
  }
  try {
    on_grid_(sample);
  } catch (const std::exception&) {
    std::lock_guard<std::mutex> lock(mutex_);
    --stats_.grids_published;
    ++stats_.sink_errors;
  }
}

}  // namespace cblox
