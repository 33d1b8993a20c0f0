#pragma once

// cblox-mapper's planner interface on LCM: distance requests (CBLOX_DISTANCE_REQUEST) handed
// to the PlanningService and its replies published (CBLOX_DISTANCE_REPLY), and its local
// grids published (CBLOX_LOCAL_GRID, zlib-compressed).

#include <memory>
#include <string>

#include <cblox/distance_request_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/mapping/mapper.h"
#include "core/mapping/planning_service.h"
#include "daemon/common/heartbeat.h"
#include "daemon/common/message_guard.h"
#include "daemon/mapper/mapper_process_config.h"

namespace cblox {

/// LCM <-> PlanningService. The request handler runs on the LCM thread and only bounds and
/// queues (PlanningService::submit); answers and grids are published from the service's
/// worker. Thread-safety: subscribe() once before the LCM thread handles messages; addTo()
/// from any thread.
class PlanningNode {
 public:
  /// `config`, `lcm` and `mapper` must outlive the node. The service starts here (it
  /// answers kNoPlanningMap when the mapper keeps no distance field).
  PlanningNode(const MapperProcessConfig& config, lcm::LCM* lcm, Mapper* mapper);

  /// Subscribes the request channel through `guard`: an undecodable request is counted as
  /// the mapper's distance_request_invalid problem.
  void subscribe(MessageGuard* guard);
  /// The service's counters and answer time (heartbeat).
  void addTo(HeartbeatBuilder* heartbeat) const;

 private:
  void onRequest(const distance_request_t& msg);
  void publishReply(const DistanceReply& reply);
  void publishGrid(const LocalGridSample& sample);

  const MapperProcessConfig& config_;
  lcm::LCM* lcm_;
  Mapper* mapper_;
  std::unique_ptr<PlanningService> service_;
};

}  // namespace cblox
