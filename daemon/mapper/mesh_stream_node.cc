#include "daemon/mapper/mesh_stream_node.h"

#include <cmath>

#include "daemon/common/mesh_stream_codec.h"
#include "daemon/common/run_loop.h"

namespace cblox {

void MeshStreamNode::attach(Mapper* mapper) {
  if (!config_.mapper.mesh_stream.enabled) return;
  mapper->setMeshStreamSinks(
      [this](const MeshUpdate& update) {
        const mesh_update_t msg = encodeMeshUpdate(update, wallUtime());
        wire_bytes_.fetch_add(static_cast<uint64_t>(msg.getEncodedSize()), std::memory_order_relaxed);
        lcm_->publish(config_.mesh_update_channel, &msg);
      },
      [this](const SubvolumeList& list) {
        const subvolume_list_t msg = encodeSubvolumeList(list, wallUtime());
        lcm_->publish(config_.subvolumes_channel, &msg);
      });
}

void MeshStreamNode::addTo(HeartbeatBuilder* heartbeat, const MeshStreamStats& s) const {
  heartbeat->add("mesh_updates_sent", s.messages)
      .add("mesh_blocks_sent", s.blocks_sent)
      .add("mesh_bytes_sent", wire_bytes_.load(std::memory_order_relaxed))
      .add("mesh_refreshes", s.refreshes)
      .add("mesh_blocks_pending", static_cast<uint64_t>(s.blocks_pending))
      .add("mesh_blocks_refused", s.blocks_refused)
      .add("mesh_period_us_median",
           static_cast<uint64_t>(std::lround(s.period_ms_median * 1000.0)))
      .add("mesh_period_us_p99", static_cast<uint64_t>(std::lround(s.period_ms_p99 * 1000.0)));
}

}  // namespace cblox
