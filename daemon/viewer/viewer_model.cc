#include "daemon/viewer/viewer_model.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

namespace cblox {
namespace {

using Json = nlohmann::json;

constexpr uint32_t kMeshMessageType = 1;
constexpr uint32_t kFlagClear = 1;

// Little-endian appends (x86 and ARM hosts are little-endian; the format is defined so).
template <typename T>
void put(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out->append(bytes, sizeof(T));
}
void pad4(std::string* out) {
  while (out->size() % 4 != 0) out->push_back('\0');
}

// A block's bytes in the message (beyond the 44-byte block header).
size_t blockBytes(const QuantizedBlockMesh& m) {
  const size_t n = m.positions.size(), t = m.triangles.size();
  const auto up4 = [](size_t b) { return (b + 3) / 4 * 4; };
  return 44 + up4(6 * n) + up4(m.colors.empty() ? 0 : 3 * n) + up4(6 * t);
}

void appendBlock(std::string* out, SubmapId id, uint64_t key, const QuantizedBlockMesh* mesh) {
  put<double>(out, static_cast<double>(id));
  const BlockIndex index = unpackGridIndex(key);
  for (int a = 0; a < 3; ++a) put<int32_t>(out, index[a]);
  const uint32_t n = mesh ? static_cast<uint32_t>(mesh->positions.size()) : 0;
  const uint32_t t = mesh ? static_cast<uint32_t>(mesh->triangles.size()) : 0;
  const bool color = mesh && !mesh->colors.empty();
  put<uint32_t>(out, n);
  put<uint32_t>(out, t);
  put<uint32_t>(out, color ? 1 : 0);
  if (!mesh) return;
  for (const auto& p : mesh->positions) {
    for (const int16_t v : p) put<int16_t>(out, v);
  }
  pad4(out);
  if (color) {
    for (const auto& c : mesh->colors) out->append(reinterpret_cast<const char*>(c.data()), 3);
    pad4(out);
  }
  for (const auto& tri : mesh->triangles) {
    for (const int16_t v : tri) put<uint16_t>(out, static_cast<uint16_t>(v));
  }
  pad4(out);
}

Json poseJson(const Transformationd& T) {
  const Eigen::Matrix4d M = T.matrix();
  Json m = Json::array();
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) m.push_back(M(r, c));  // column-major, as three.js takes it
  }
  return m;
}

Json vec(const Eigen::Vector3f& v) { return Json::array({v.x(), v.y(), v.z()}); }

}  // namespace

ViewerModel::ViewerModel(Settings settings) : settings_(std::move(settings)) {}

void ViewerModel::markAll(const std::function<void(Outbox&)>& mark) {
  for (auto& [id, outbox] : clients_) mark(outbox);
  work_.notify_all();
}

MeshMirror::Result ViewerModel::applyMeshUpdate(const MeshUpdate& update) {
  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t epoch_before = mirror_.mapEpoch();
  const bool had_any = mirror_.lastSequence() != 0;
  const MeshMirror::Result result = mirror_.apply(update);
  if (!result.applied) return result;
  if (update.refresh_start || mirror_.mapEpoch() != epoch_before) {
    markAll([](Outbox& o) {
      o.full_mesh = true;
      o.dirty_blocks.clear();
      o.removed.clear();
      o.state = true;
    });
    if (had_any && mirror_.mapEpoch() != epoch_before) {
      addEventLocked(0, "map", "the mapper started a new map");
    }
    return result;
  }
  markAll([&](Outbox& o) {
    for (const SubmapId id : update.removed_submaps) {
      o.removed.insert(id);
      for (auto it = o.dirty_blocks.begin(); it != o.dirty_blocks.end();) {
        it = it->first == id ? o.dirty_blocks.erase(it) : std::next(it);
      }
    }
    for (const MeshBlockUpdate& b : update.blocks) {
      o.dirty_blocks.insert({b.submap, packGridIndex(b.index)});
    }
    o.state = true;  // completeness, pending counts
  });
  return result;
}

void ViewerModel::applySubvolumes(const SubvolumeList& list, int64_t utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (list.map_epoch == previous_list_.map_epoch) {
    std::set<SubmapId> now;
    for (const SubvolumeView& v : list.subvolumes) now.insert(v.id);
    for (const SubvolumeView& v : previous_list_.subvolumes) {
      if (!now.count(v.id)) {
        addEventLocked(utime, "fusion",
                       "subvolume " + std::to_string(v.id) + " left the map (fused)");
      }
    }
  }
  mirror_.applySubvolumes(list);
  previous_list_ = list;
  markAll([](Outbox& o) { o.state = true; });
}

void ViewerModel::addVehiclePose(int64_t utime, const Transformationd& T_G_C, bool from_tracker,
                                 int32_t epoch) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (from_tracker) {
    if (!tracker_poses_ || epoch != tracker_epoch_) {
      if (tracker_poses_) addEventLocked(utime, "map", "the tracker started a new map");
      trajectory_.clear();
      keyframes_.clear();
      ++trajectory_generation_;
      markAll([](Outbox& o) { o.keyframes = true; });
    }
    tracker_poses_ = true;
    tracker_epoch_ = epoch;
  } else if (tracker_poses_) {
    return;
  }
  vehicle_ = T_G_C;
  // At most 10 points a second; a new source (time going back) starts over.
  if (utime < last_pose_utime_) {
    trajectory_.clear();
    ++trajectory_generation_;
  } else if (utime - last_pose_utime_ < 100000 && !trajectory_.empty()) {
    markAll([](Outbox& o) { o.vehicle = true; });
    return;
  }
  last_pose_utime_ = utime;
  trajectory_.push_back(T_G_C.translation().cast<float>());
  if (trajectory_.size() > settings_.max_trajectory_points) {
    std::vector<Eigen::Vector3f> thinned;
    thinned.reserve(trajectory_.size() / 2 + 1);
    for (size_t i = 0; i < trajectory_.size(); i += 2) thinned.push_back(trajectory_[i]);
    trajectory_ = std::move(thinned);
    ++trajectory_generation_;
  }
  markAll([](Outbox& o) { o.vehicle = true; });
}

void ViewerModel::addKeyframe(int64_t key, const Transformationd& T_G_K) {
  std::lock_guard<std::mutex> lock(mutex_);
  keyframes_[key] = T_G_K.translation();
  markAll([](Outbox& o) { o.keyframes = true; });
}

void ViewerModel::moveKeyframes(const std::vector<std::pair<int64_t, Transformationd>>& poses,
                                bool loop_closure, int64_t utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  double largest = 0.0;
  for (const auto& [key, T] : poses) {
    const auto it = keyframes_.find(key);
    if (it == keyframes_.end()) continue;
    largest = std::max(largest, (it->second - T.translation()).norm());
    it->second = T.translation();
  }
  if (loop_closure) {
    char text[160];
    std::snprintf(text, sizeof(text), "loop closure: %zu keyframes corrected, up to %.2f m",
                  poses.size(), largest);
    addEventLocked(utime, "loop", text);
  }
  markAll([](Outbox& o) { o.keyframes = true; });
}

void ViewerModel::setFusedCount(int64_t fused, int64_t utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (fused_ >= 0 && fused > fused_) {
    addEventLocked(utime, "fusion",
                   std::to_string(fused - fused_) + " subvolume(s) fused (" +
                       std::to_string(fused) + " since the mapper started)");
  }
  fused_ = fused;
}

void ViewerModel::setHeartbeat(ProcessHealth health) {
  std::lock_guard<std::mutex> lock(mutex_);
  health_[health.name] = std::move(health);
  markAll([](Outbox& o) { o.health = true; });
}

void ViewerModel::setSlice(DistanceSlice slice) {
  std::lock_guard<std::mutex> lock(mutex_);
  slice_ = std::move(slice);
  markAll([](Outbox& o) { o.slice = true; });
}

void ViewerModel::addEvent(int64_t utime, const std::string& kind, const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  addEventLocked(utime, kind, text);
}

void ViewerModel::addEventLocked(int64_t utime, const std::string& kind,
                                 const std::string& text) {
  events_.push_back(Event{utime, kind, text});
  if (events_.size() > kMaxEvents) {
    events_.pop_front();
    ++events_dropped_;
  }
  work_.notify_all();
}

void ViewerModel::setExportResult(int64_t id, bool ok, const std::string& message,
                                  const std::string& file) {
  std::lock_guard<std::mutex> lock(mutex_);
  exports_[id] = ExportResult{ok, message, file};
  while (exports_.size() > 16) exports_.erase(exports_.begin());
  last_export_ = id;
  markAll([](Outbox& o) { o.export_result = true; });
}

std::string ViewerModel::exportFile(int64_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = exports_.find(id);
  return it != exports_.end() && it->second.ok ? it->second.file : std::string();
}

int ViewerModel::addClient() {
  std::lock_guard<std::mutex> lock(mutex_);
  const int id = next_client_++;
  clients_[id] = Outbox{};
  clients_[id].slice = slice_.has_value();
  return id;
}

void ViewerModel::removeClient(int client) {
  std::lock_guard<std::mutex> lock(mutex_);
  clients_.erase(client);
}

bool ViewerModel::hasWork(const Outbox& o) const {
  return o.state || o.vehicle || o.full_mesh || !o.dirty_blocks.empty() || !o.removed.empty() ||
         o.keyframes || o.health || o.slice || o.export_result ||
         o.trajectory_generation != trajectory_generation_ ||
         o.trajectory_sent != trajectory_.size() ||
         o.events_sent != events_dropped_ + events_.size();
}

bool ViewerModel::waitForWork(int client, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  return work_.wait_for(lock, timeout, [&] {
    const auto it = clients_.find(client);
    return it == clients_.end() || hasWork(it->second);
  });
}

void ViewerModel::wakeAll() {
  std::lock_guard<std::mutex> lock(mutex_);
  work_.notify_all();
}

std::string ViewerModel::stateJson() const {
  Json j;
  j["type"] = "state";
  j["map_epoch"] = mirror_.mapEpoch();
  j["block_size"] = mirror_.blockSize();
  j["synced"] = mirror_.synced();
  j["complete"] = mirror_.complete();
  j["up_axis"] = settings_.up_axis;
  j["allow_export"] = settings_.allow_export;
  const SubvolumeList& list = mirror_.subvolumes();
  j["active"] = list.active_submap;
  j["subvolumes_epoch_matches"] = list.map_epoch == mirror_.mapEpoch();
  Json subs = Json::array();
  for (const SubvolumeView& v : list.subvolumes) {
    const auto held = mirror_.blocks().find(v.id);
    subs.push_back({{"id", v.id},
                    {"pose", poseJson(v.T_G_S)},
                    {"active", v.active},
                    {"blocks", v.num_blocks},
                    {"mesh_blocks", held == mirror_.blocks().end() ? 0 : held->second.size()},
                    {"min", vec(v.min_S)},
                    {"max", vec(v.max_S)}});
  }
  j["subvolumes"] = std::move(subs);
  return j.dump();
}

std::string ViewerModel::meshMessage(Outbox* o, size_t max_mesh_bytes) {
  std::string out;
  uint32_t flags = 0;
  if (o->full_mesh) {
    flags |= kFlagClear;
    o->full_mesh = false;
    o->removed.clear();
    o->dirty_blocks.clear();
    for (const auto& [id, blocks] : mirror_.blocks()) {
      for (const auto& [key, mesh] : blocks) o->dirty_blocks.insert({id, key});
    }
  }
  put<uint32_t>(&out, kMeshMessageType);
  put<uint32_t>(&out, flags);
  put<float>(&out, mirror_.blockSize());
  put<uint32_t>(&out, static_cast<uint32_t>(o->removed.size()));
  const size_t count_at = out.size();
  put<uint32_t>(&out, 0);
  for (const SubmapId id : o->removed) put<double>(&out, static_cast<double>(id));
  o->removed.clear();
  uint32_t count = 0;
  size_t bytes = 0;
  for (auto it = o->dirty_blocks.begin(); it != o->dirty_blocks.end();) {
    const QuantizedBlockMesh* mesh = nullptr;
    const auto sub = mirror_.blocks().find(it->first);
    if (sub != mirror_.blocks().end()) {
      const auto block = sub->second.find(it->second);
      if (block != sub->second.end()) mesh = &block->second;
    }
    const size_t cost = mesh ? blockBytes(*mesh) : 44;
    if (count > 0 && bytes + cost > max_mesh_bytes) break;
    appendBlock(&out, it->first, it->second, mesh);
    bytes += cost;
    ++count;
    it = o->dirty_blocks.erase(it);
  }
  std::memcpy(&out[count_at], &count, sizeof(count));
  return out;
}

bool ViewerModel::nextMessage(int client, size_t max_mesh_bytes, BrowserMessage* out) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = clients_.find(client);
  if (it == clients_.end()) return false;
  Outbox& o = it->second;
  out->binary = false;
  if (o.state) {
    o.state = false;
    out->data = stateJson();
    return true;
  }
  if (o.full_mesh || !o.dirty_blocks.empty() || !o.removed.empty()) {
    out->binary = true;
    out->data = meshMessage(&o, max_mesh_bytes);
    return true;
  }
  if (o.vehicle) {
    o.vehicle = false;
    if (vehicle_) {
      Json j;
      j["type"] = "vehicle";
      j["pose"] = poseJson(*vehicle_);
      out->data = j.dump();
      return true;
    }
  }
  if (o.trajectory_generation != trajectory_generation_ || o.trajectory_sent != trajectory_.size()) {
    Json j;
    j["type"] = "trajectory";
    const bool reset = o.trajectory_generation != trajectory_generation_ ||
                       o.trajectory_sent > trajectory_.size();
    j["reset"] = reset;
    const size_t from = reset ? 0 : o.trajectory_sent;
    Json points = Json::array();
    for (size_t i = from; i < trajectory_.size(); ++i) {
      points.push_back(trajectory_[i].x());
      points.push_back(trajectory_[i].y());
      points.push_back(trajectory_[i].z());
    }
    j["points"] = std::move(points);
    o.trajectory_generation = trajectory_generation_;
    o.trajectory_sent = trajectory_.size();
    out->data = j.dump();
    return true;
  }
  if (o.keyframes) {
    o.keyframes = false;
    Json j;
    j["type"] = "keyframes";
    Json points = Json::array();
    for (const auto& [key, p] : keyframes_) {
      points.push_back(p.x());
      points.push_back(p.y());
      points.push_back(p.z());
    }
    j["points"] = std::move(points);
    out->data = j.dump();
    return true;
  }
  const size_t events_total = events_dropped_ + events_.size();
  if (o.events_sent != events_total) {
    Json j;
    j["type"] = "events";
    Json list = Json::array();
    const size_t first = std::max(o.events_sent, events_dropped_) - events_dropped_;
    for (size_t i = first; i < events_.size(); ++i) {
      list.push_back({{"utime", events_[i].utime}, {"kind", events_[i].kind}, {"text", events_[i].text}});
    }
    j["events"] = std::move(list);
    o.events_sent = events_total;
    out->data = j.dump();
    return true;
  }
  if (o.health) {
    o.health = false;
    Json j;
    j["type"] = "health";
    Json list = Json::array();
    for (const auto& [name, h] : health_) {
      Json counters = Json::object();
      for (const auto& [k, v] : h.counters) counters[k] = v;
      list.push_back({{"name", h.name}, {"pid", h.pid}, {"state", h.state}, {"utime", h.utime},
                      {"counters", std::move(counters)}});
    }
    j["processes"] = std::move(list);
    out->data = j.dump();
    return true;
  }
  if (o.slice && slice_) {
    o.slice = false;
    Json j;
    j["type"] = "slice";
    j["axes"] = {slice_->axis_u, slice_->axis_v};
    j["origin"] = {slice_->origin.x(), slice_->origin.y()};
    j["level"] = slice_->level;
    j["resolution"] = slice_->resolution;
    j["nu"] = slice_->nu;
    j["nv"] = slice_->nv;
    j["max_distance_m"] = slice_->max_distance_m;
    Json cells = Json::array();
    for (size_t i = 0; i < slice_->distance_mm.size(); ++i) {
      if (slice_->state[i] == 0) {
        cells.push_back(nullptr);
      } else {
        cells.push_back(slice_->distance_mm[i]);
      }
    }
    j["distance_mm"] = std::move(cells);
    out->data = j.dump();
    return true;
  }
  o.slice = false;
  if (o.export_result) {
    o.export_result = false;
    const auto e = exports_.find(last_export_);
    if (e == exports_.end()) return false;
    Json j;
    j["type"] = "export";
    j["id"] = e->first;
    j["ok"] = e->second.ok;
    j["message"] = e->second.message;
    if (e->second.ok) j["url"] = "/export/" + std::to_string(e->first) + ".ply";
    out->data = j.dump();
    return true;
  }
  return false;
}

bool ViewerModel::meshSynced() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return mirror_.synced();
}

bool ViewerModel::meshComplete() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return mirror_.complete();
}

size_t ViewerModel::numBlocks() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return mirror_.numBlocks();
}

size_t ViewerModel::numClients() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return clients_.size();
}

}  // namespace cblox
