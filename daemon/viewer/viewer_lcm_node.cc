#include "daemon/viewer/viewer_lcm_node.h"

#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include <cblox/command_t.hpp>

#include "core/mapping/map_epoch_key.h"
#include "daemon/common/lcm_messages.h"
#include "daemon/common/local_grid_codec.h"
#include "daemon/common/mesh_stream_codec.h"
#include "daemon/common/run_loop.h"

namespace cblox {
namespace {

// The index of the up axis ("z" -> 2, "-y" -> 1, ...).
int upAxisIndex(const std::string& up) { return up.back() - 'x'; }

}  // namespace

ViewerLcmNode::ViewerLcmNode(const ViewerConfig& config, lcm::LCM* lcm, ViewerModel* model)
    : config_(config),
      lcm_(lcm),
      model_(model),
      guard_(lcm),
      refusal_log_(2, std::chrono::seconds(10),
                   [](const std::string& line) {
                     std::fprintf(stderr, "cblox-viewer: %s\n", line.c_str());
                   }),
      id_base_(wallUtime() * 1000) {}

void ViewerLcmNode::refuse(bool mesh, const std::string& why) {
  (mesh ? mesh_refused_ : bad_messages_).fetch_add(1, std::memory_order_relaxed);
  refusal_log_.report(mesh ? 0 : 1, std::string(mesh ? "mesh update" : "message") +
                                        " refused: " + why);
}

void ViewerLcmNode::subscribe() {
  const MessageGuard::RefusedCallback refused = nullptr;  // the guard counts and logs them
  guard_.subscribe<mesh_update_t>(
      config_.mesh_update_channel,
      [this](const mesh_update_t& m, const std::string&) { onMeshUpdate(m); }, refused);
  guard_.subscribe<subvolume_list_t>(
      config_.subvolumes_channel,
      [this](const subvolume_list_t& m, const std::string&) { onSubvolumes(m); }, refused);
  guard_.subscribe<frame_pose_t>(
      config_.frame_pose_channel,
      [this](const frame_pose_t& m, const std::string&) { onFramePose(m); }, refused);
  guard_.subscribe<pose_stamped_t>(
      config_.ground_truth_channel,
      [this](const pose_stamped_t& m, const std::string&) { onGroundTruth(m); }, refused);
  guard_.subscribe<keyframe_t>(
      config_.keyframe_channel,
      [this](const keyframe_t& m, const std::string&) { onKeyframe(m); }, refused);
  guard_.subscribe<keyframe_pose_batch_t>(
      config_.keyframe_poses_channel,
      [this](const keyframe_pose_batch_t& m, const std::string&) { onKeyframePoses(m); },
      refused);
  guard_.subscribe<map_status_t>(
      config_.map_status_channel,
      [this](const map_status_t& m, const std::string&) { onMapStatus(m); }, refused);
  guard_.subscribe<heartbeat_t>(
      config_.heartbeat_channel,
      [this](const heartbeat_t& m, const std::string&) { onHeartbeat(m); }, refused);
  guard_.subscribe<local_grid_t>(
      config_.local_grid_channel,
      [this](const local_grid_t& m, const std::string&) { onLocalGrid(m); }, refused);
  guard_.subscribe<command_reply_t>(
      config_.command_reply_channel,
      [this](const command_reply_t& m, const std::string&) { onCommandReply(m); }, refused);
}

void ViewerLcmNode::onMeshUpdate(const mesh_update_t& msg) {
  MeshUpdate update;
  std::string error;
  if (!decodeMeshUpdate(msg, &update, &error)) return refuse(true, error);
  const MeshMirror::Result r = model_->applyMeshUpdate(update);
  if (!r.applied) return refuse(true, r.error);
  mesh_updates_.fetch_add(1, std::memory_order_relaxed);
  if (r.gap) mesh_gaps_.fetch_add(1, std::memory_order_relaxed);
}

void ViewerLcmNode::onSubvolumes(const subvolume_list_t& msg) {
  SubvolumeList list;
  std::string error;
  if (!decodeSubvolumeList(msg, &list, &error)) return refuse(false, error);
  model_->applySubvolumes(list, msg.utime);
}

void ViewerLcmNode::onFramePose(const frame_pose_t& msg) {
  if (msg.tracking_state == frame_pose_t::NOT_INITIALIZED ||
      msg.tracking_state == frame_pose_t::LOST) {
    return;
  }
  std::string error;
  const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_C, &error);
  if (!T) return refuse(false, error);
  model_->addVehiclePose(msg.utime, *T, true, msg.map_epoch);
}

void ViewerLcmNode::onGroundTruth(const pose_stamped_t& msg) {
  std::string error;
  const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_C, &error);
  if (!T) return refuse(false, error);
  model_->addVehiclePose(msg.utime, *T, false, 0);
}

void ViewerLcmNode::onKeyframe(const keyframe_t& msg) {
  std::string error;
  const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_K, &error);
  const std::optional<int64_t> key = epochKey(msg.map_epoch, msg.keyframe_id);
  if (!T || !key) return refuse(false, error.empty() ? "keyframe id or epoch out of range" : error);
  model_->addKeyframe(*key, *T);
}

void ViewerLcmNode::onKeyframePoses(const keyframe_pose_batch_t& msg) {
  std::vector<std::pair<int64_t, Transformationd>> poses;
  for (size_t i = 0; i < msg.keyframe_ids.size() && i < msg.poses.size(); ++i) {
    std::string error;
    const std::optional<Transformationd> T = fromPoseMsg(msg.poses[i], &error);
    const std::optional<int64_t> key = epochKey(msg.map_epoch, msg.keyframe_ids[i]);
    if (!T || !key) {
      refuse(false, error.empty() ? "keyframe id or epoch out of range" : error);
      continue;
    }
    poses.emplace_back(*key, *T);
  }
  model_->moveKeyframes(poses, msg.reason == keyframe_pose_batch_t::LOOP_CORRECTION, msg.utime);
}

void ViewerLcmNode::onMapStatus(const map_status_t& msg) {
  model_->setFusedCount(msg.subvolumes_fused, msg.utime);
}

void ViewerLcmNode::onHeartbeat(const heartbeat_t& msg) {
  ProcessHealth h;
  // Bounded: a process name is a short identifier; anything longer is not one of ours.
  h.name = msg.process.substr(0, 64);
  h.pid = msg.pid;
  h.state = msg.state.substr(0, 256);
  h.utime = msg.utime;
  const size_t n = std::min<size_t>({msg.counter_names.size(), msg.counter_values.size(), 256});
  for (size_t i = 0; i < n; ++i) h.counters.emplace_back(msg.counter_names[i].substr(0, 64), msg.counter_values[i]);
  model_->setHeartbeat(std::move(h));
}

void ViewerLcmNode::onLocalGrid(const local_grid_t& msg) {
  LocalGridSample sample;
  std::string error;
  if (!decodeLocalGrid(msg, &sample, &error)) return refuse(false, error);
  const LocalGrid& g = sample.grid;
  const int up = upAxisIndex(config_.up_axis);
  const int u = up == 0 ? 1 : 0, v = up == 2 ? 1 : 2;
  // The layer through the box's centre (the grid is centred on the vehicle).
  const int layer = g.size[up] / 2;
  DistanceSlice s;
  s.axis_u = u;
  s.axis_v = v;
  s.origin = Eigen::Vector2d(g.origin[u], g.origin[v]);
  s.level = g.origin[up] + (layer + 0.5) * g.resolution;
  s.resolution = g.resolution;
  s.nu = g.size[u];
  s.nv = g.size[v];
  s.max_distance_m = sample.max_distance_m;
  s.distance_mm.reserve(static_cast<size_t>(s.nu) * static_cast<size_t>(s.nv));
  for (int jv = 0; jv < s.nv; ++jv) {
    for (int iu = 0; iu < s.nu; ++iu) {
      Eigen::Vector3i c;
      c[up] = layer;
      c[u] = iu;
      c[v] = jv;
      const size_t k = g.index(c[0], c[1], c[2]);
      s.state.push_back(static_cast<int8_t>(g.state[k]));
      const float d = g.distance[k];
      s.distance_mm.push_back(std::isfinite(d) ? static_cast<int32_t>(std::lround(d * 1000.0f)) : 0);
    }
  }
  model_->setSlice(std::move(s));
}

void ViewerLcmNode::onCommandReply(const command_reply_t& msg) {
  if (msg.command_id != pending_export_.load()) return;
  pending_export_ = -1;
  std::string file;
  for (size_t i = 0; i < msg.value_keys.size() && i < msg.values.size(); ++i) {
    if (msg.value_keys[i] == "path") file = msg.values[i];
  }
  const int64_t id = msg.command_id - id_base_;
  model_->setExportResult(id, msg.ok && !file.empty(), msg.message.substr(0, 512), file);
  model_->addEvent(msg.utime, "export", msg.ok ? "mesh exported: " + file : "export failed: " + msg.message.substr(0, 512));
}

void ViewerLcmNode::publishCommand(int64_t id, const std::string& name, const std::string& path) {
  command_t cmd;
  cmd.utime = wallUtime();
  cmd.command_id = id;
  cmd.sender = "cblox-viewer";
  cmd.name = name;
  if (!path.empty()) {
    cmd.arg_keys = {"path"};
    cmd.arg_values = {path};
  }
  cmd.num_args = static_cast<int32_t>(cmd.arg_keys.size());
  std::lock_guard<std::mutex> lock(publish_mutex_);
  lcm_->publish(config_.command_channel, &cmd);
}

void ViewerLcmNode::tick() {
  const auto now = std::chrono::steady_clock::now();
  if (model_->meshSynced()) return;
  if (asked_once_ && now - last_refresh_request_ <
                         std::chrono::duration<double>(config_.refresh_retry_s)) {
    return;
  }
  asked_once_ = true;
  last_refresh_request_ = now;
  refresh_requests_.fetch_add(1, std::memory_order_relaxed);
  publishCommand(id_base_ + next_command_.fetch_add(1), "mesh_refresh", "");
}

void ViewerLcmNode::requestExport() {
  const int64_t n = next_command_.fetch_add(1);
  pending_export_ = id_base_ + n;
  exports_requested_.fetch_add(1, std::memory_order_relaxed);
  publishCommand(id_base_ + n, "export_mesh", "viewer_export_" + std::to_string(n) + ".ply");
}

ViewerLcmCounters ViewerLcmNode::counters() const {
  ViewerLcmCounters c;
  c.mesh_updates = mesh_updates_.load();
  c.mesh_refused = mesh_refused_.load();
  c.mesh_gaps = mesh_gaps_.load();
  c.refresh_requests = refresh_requests_.load();
  c.exports_requested = exports_requested_.load();
  c.bad_messages = bad_messages_.load();
  return c;
}

void ViewerLcmNode::addTo(HeartbeatBuilder* heartbeat) const {
  const ViewerLcmCounters c = counters();
  heartbeat->add("mesh_updates_applied", c.mesh_updates)
      .add("mesh_updates_refused", c.mesh_refused)
      .add("mesh_gaps", c.mesh_gaps)
      .add("mesh_refresh_requests", c.refresh_requests)
      .add("exports_requested", c.exports_requested)
      .add("messages_refused", c.bad_messages)
      .add("mesh_blocks", static_cast<uint64_t>(model_->numBlocks()));
  guard_.addTo(heartbeat);
}

}  // namespace cblox
