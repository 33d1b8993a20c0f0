#include "daemon/mapper/planning_node.h"

#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include <cblox/distance_reply_t.hpp>
#include <cblox/local_grid_t.hpp>

#include "daemon/common/local_grid_codec.h"
#include "daemon/common/run_loop.h"

namespace cblox {

namespace {

static_assert(static_cast<int>(DistanceStatus::kOk) == distance_reply_t::STATUS_OK);
static_assert(static_cast<int>(DistanceStatus::kEpochChanged) ==
              distance_reply_t::STATUS_EPOCH_CHANGED);
static_assert(static_cast<int>(DistanceStatus::kTooManyPoints) ==
              distance_reply_t::STATUS_TOO_MANY_POINTS);
static_assert(static_cast<int>(DistanceStatus::kNoPlanningMap) ==
              distance_reply_t::STATUS_NO_PLANNING_MAP);
static_assert(static_cast<int>(DistanceStatus::kBusy) == distance_reply_t::STATUS_BUSY);

// The wire's states are VoxelState's values, and INVALID_POINT.
static_assert(static_cast<int>(VoxelState::kUnknown) == distance_reply_t::UNKNOWN);
static_assert(static_cast<int>(VoxelState::kFree) == distance_reply_t::FREE);
static_assert(static_cast<int>(VoxelState::kOccupied) == distance_reply_t::OCCUPIED);

int8_t wireState(const DistanceAnswer& a, bool invalid) {
  return invalid ? distance_reply_t::INVALID_POINT : static_cast<int8_t>(a.state);
}

}  // namespace

PlanningNode::PlanningNode(const MapperProcessConfig& config, lcm::LCM* lcm, Mapper* mapper)
    : config_(config), lcm_(lcm), mapper_(mapper) {
  PlanningServiceConfig service = config_.mapper.planning.service;
  service.max_points = static_cast<size_t>(distance_request_t::MAX_POINTS);
  service_ = std::make_unique<PlanningService>(
      service, mapper_->planningMap(), [this] { return mapper_->mapEpoch(); },
      [this]() -> std::optional<std::pair<int64_t, Transformationd>> {
        const std::optional<TimedPose> pose = mapper_->newestPose();
        if (!pose) return std::nullopt;
        return std::make_pair(pose->utime, pose->T_G_C);
      },
      [this](const DistanceReply& reply) { publishReply(reply); },
      [this](const LocalGridSample& sample) { publishGrid(sample); });
}

void PlanningNode::subscribe(MessageGuard* guard) {
  guard->subscribe<distance_request_t>(
      config_.distance_request_channel,
      [this](const distance_request_t& m, const std::string&) { onRequest(m); },
      [this](const std::string& description) {
        mapper_->reportProblem(InputProblem::kDistanceRequestInvalid, description);
      });
}

void PlanningNode::onRequest(const distance_request_t& msg) {
  // The wire check has bounded points by the message's bytes; num_points may still exceed
  // MAX_POINTS (answered TOO_MANY_POINTS) or disagree with nothing (lcm-gen sizes points by
  // it).
  const size_t n = msg.num_points < 0 ? 0 : static_cast<size_t>(msg.num_points);
  if (n > static_cast<size_t>(distance_request_t::MAX_POINTS)) {
    mapper_->reportProblem(InputProblem::kDistanceRequestInvalid,
                           "distance request " + std::to_string(msg.request_id) + ": " +
                               std::to_string(n) + " points, more than " +
                               std::to_string(distance_request_t::MAX_POINTS));
  }
  service_->submit(msg.request_id, msg.map_epoch, n, [&msg](size_t k) {
    return Eigen::Vector3d(msg.points[k][0], msg.points[k][1], msg.points[k][2]);
  });
}

void PlanningNode::publishReply(const DistanceReply& reply) {
  distance_reply_t msg;
  msg.utime = wallUtime();
  msg.request_id = reply.request_id;
  msg.map_epoch = reply.map_epoch;
  msg.status = static_cast<int8_t>(reply.status);
  msg.message = reply.message;
  msg.max_distance_m = reply.max_distance_m;
  const size_t n = reply.answers.size();
  msg.num_points = static_cast<int32_t>(n);
  msg.state.resize(n);
  msg.distance.resize(n);
  msg.gradient.assign(n, std::vector<float>(3, std::numeric_limits<float>::quiet_NaN()));
  for (size_t k = 0; k < n; ++k) {
    const DistanceAnswer& a = reply.answers[k];
    const bool invalid = k < reply.invalid_point.size() && reply.invalid_point[k] != 0;
    msg.state[k] = wireState(a, invalid);
    msg.distance[k] = invalid ? std::numeric_limits<float>::quiet_NaN()
                              : static_cast<float>(a.distance);
    if (!invalid && a.has_gradient) {
      for (int i = 0; i < 3; ++i) msg.gradient[k][static_cast<size_t>(i)] = static_cast<float>(a.gradient[i]);
    }
  }
  lcm_->publish(config_.distance_reply_channel, &msg);
}

void PlanningNode::publishGrid(const LocalGridSample& sample) {
  const local_grid_t msg = encodeLocalGrid(sample);
  lcm_->publish(config_.local_grid_channel, &msg);
}

void PlanningNode::addTo(HeartbeatBuilder* heartbeat) const {
  const PlanningServiceStats s = service_->stats();
  heartbeat->add("distance_requests_answered", s.requests_answered)
      .add("distance_requests_refused", s.requests_refused)
      .add("distance_points_answered", s.points_answered)
      .add("local_grids_published", s.grids_published)
      .add("distance_answer_us_median",
           static_cast<uint64_t>(std::lround(service_->answerMs().quantile(0.5) * 1000.0)))
      .add("distance_answer_us_p99",
           static_cast<uint64_t>(std::lround(service_->answerMs().quantile(0.99) * 1000.0)));
}

}  // namespace cblox
