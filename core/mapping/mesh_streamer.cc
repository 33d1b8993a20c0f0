#include "core/mapping/mesh_streamer.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include <absl/container/flat_hash_set.h>

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

// Budget bytes a block costs beyond its mesh (id, index, counts: mesh_block_t's fixed part).
constexpr size_t kBlockOverheadBytes = 32;

MeshStreamConfig validated(const MeshStreamConfig& config) {
  if (const std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("MeshStreamConfig: " + e);
  }
  return config;
}

// The stream's mesher settings: colours as configured, no normals (receivers compute them),
// one thread (the worker's).
MeshConfig streamMeshConfig(const MeshConfig& mesh, const MeshStreamConfig& stream) {
  MeshConfig c = mesh;
  c.use_color = stream.use_color;
  c.compute_normals = false;
  c.num_threads = 1;
  if (const std::string e = c.validate(); !e.empty()) {
    throw std::invalid_argument("MeshConfig: " + e);
  }
  return c;
}

}  // namespace

size_t MeshUpdate::payloadBytes() const {
  size_t bytes = 0;
  for (const MeshBlockUpdate& b : blocks) bytes += b.mesh.payloadBytes();
  return bytes;
}

MeshStreamer::MeshStreamer(const MeshStreamConfig& config, const MeshConfig& mesh,
                           const SubmapCollection* collection,
                           std::function<int64_t()> map_epoch, int copy_niceness,
                           UpdateSink on_update, SubvolumeSink on_subvolumes, LogSink log)
    : config_(validated(config)),
      mesh_config_(streamMeshConfig(mesh, config)),
      collection_(collection),
      map_epoch_(std::move(map_epoch)),
      on_update_(std::move(on_update)),
      on_subvolumes_(std::move(on_subvolumes)),
      log_(std::move(log)),
      block_size_(static_cast<double>(collection->config().layer.voxel_size) *
                  collection->config().layer.voxels_per_side),
      copier_("cblox-meshcopy", copy_niceness),
      mesher_(mesh_config_) {}

MeshStreamer::~MeshStreamer() { stop(); }

void MeshStreamer::start() {
  copier_.start();
  copier_running_ = true;
}

void MeshStreamer::stop() {
  copier_.stop();
  copier_running_ = false;
}

MeshStreamStats MeshStreamer::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  MeshStreamStats s = stats_;
  s.period_ms_median = static_cast<float>(period_ms_.quantile(0.5));
  s.period_ms_p99 = static_cast<float>(period_ms_.quantile(0.99));
  return s;
}

std::vector<uint64_t> MeshStreamer::scan(const TsdfLayer& layer, SubmapState* st,
                                         bool everything) const {
  absl::flat_hash_set<uint64_t> dirty;
  const auto add_lower_neighbours = [&](const BlockIndex& index) {
    for (const auto& o : kMeshLowerNeighbours) {
      const BlockIndex neighbour = index + BlockIndex(o[0], o[1], o[2]);
      if (layer.getBlock(neighbour) != nullptr) dirty.insert(packGridIndex(neighbour));
    }
  };
  // Blocks that left the layer: their lower neighbours' cubes lost corners; a block the
  // receivers hold a surface of is sent as a removal (an empty mesh).
  std::vector<uint64_t> forget;
  for (auto& [key, record] : st->blocks) {
    if (!record.in_layer || layer.getBlock(unpackGridIndex(key)) != nullptr) continue;
    record.in_layer = false;
    st->bounds_stale = true;
    add_lower_neighbours(unpackGridIndex(key));
    if (record.has_surface) {
      st->pending[key] = QuantizedBlockMesh{};
    } else {
      forget.push_back(key);
    }
  }
  for (const uint64_t key : forget) st->blocks.erase(key);

  for (const auto& [key, block] : layer.blocks()) {
    const uint64_t count = block->changeCount();
    const auto [it, inserted] = st->blocks.try_emplace(key);
    BlockRecord& record = it->second;
    if (!everything && !inserted && record.in_layer && record.change_count == count) continue;
    record.change_count = count;
    record.in_layer = true;
    dirty.insert(key);
    add_lower_neighbours(block->index());
  }
  if (!dirty.empty()) st->bounds_stale = true;
  std::vector<uint64_t> keys(dirty.begin(), dirty.end());
  std::sort(keys.begin(), keys.end());
  return keys;
}

void MeshStreamer::scanFinished(const Submap& submap, SubmapState* st, bool everything) {
  // A finished layer is written only by this thread (fusion), after revision() moved.
  const uint64_t revision = submap.revision();
  if (!everything && revision == st->revision) return;
  st->revision = revision;
  for (const uint64_t key : scan(submap.layer(), st, everything)) st->pending[key] = std::nullopt;
}

void MeshStreamer::scanActive(const Submap& submap, SubmapState* st, bool everything) {
  if (!everything && submap.revision() == st->revision) return;
  TsdfLayer copy(submap.layerConfig());
  std::vector<uint64_t> dirty;
  bool finished = false;
  const std::function<void()> job = [&] {
    std::unique_lock<std::mutex> lock = submap.lockLayer();
    if (submap.isFinished()) {
      finished = true;
      return;
    }
    // Under the layer lock: the integrator bumps revision() before it releases the lock, so
    // this revision is that of the blocks copied below.
    st->revision = submap.revision();
    const TsdfLayer& layer = submap.layer();
    dirty = scan(layer, st, everything);
    // A block's mesh reads it and its 7 upper neighbours.
    for (const uint64_t key : dirty) {
      const BlockIndex index = unpackGridIndex(key);
      for (int o = 0; o < 8; ++o) {
        const BlockIndex source_index = index + BlockIndex(o & 1, (o >> 1) & 1, (o >> 2) & 1);
        const Block* source = layer.getBlock(source_index);
        if (source == nullptr || copy.getBlock(source_index) != nullptr) continue;
        Block* target = copy.allocateBlock(source_index);
        std::copy_n(source->voxels(), source->numVoxels(), target->voxels());
      }
    }
  };
  if (copier_running_) {
    if (!copier_.run(job)) return;  // stopping
  } else {
    job();
  }
  if (finished) {
    scanFinished(submap, st, everything);
    return;
  }
  for (const uint64_t key : dirty) {
    QuantizedBlockMesh mesh;
    if (meshBlock(copy, key, &mesh)) st->pending[key] = std::move(mesh);
  }
}

bool MeshStreamer::meshBlock(const TsdfLayer& layer, uint64_t key, QuantizedBlockMesh* out) {
  const BlockIndex index = unpackGridIndex(key);
  const Block* block = layer.getBlock(index);
  if (block == nullptr) {  // left the layer since it was marked: a removal
    *out = QuantizedBlockMesh{};
    return true;
  }
  mesher_.meshBlock(layer, *block, &scratch_mesh_);
  const Eigen::Vector3d center = (index.cast<double>() + Eigen::Vector3d::Constant(0.5)) * block_size_;
  std::string error;
  if (quantizeBlockMesh(scratch_mesh_, center, block_size_, out, &error)) return true;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.blocks_refused;
  }
  if (log_) {
    log_("mesh stream: block (" + std::to_string(index.x()) + ", " + std::to_string(index.y()) +
         ", " + std::to_string(index.z()) + ") not sent: " + error);
  }
  return false;
}

void MeshStreamer::send(const std::vector<std::shared_ptr<Submap>>& submaps,
                        std::vector<SubmapId> removed, bool refresh_start) {
  size_t pending = 0;
  for (const auto& [id, st] : state_) pending += st.pending.size();

  // The active subvolume first (what is being mapped now), then the others by id.
  std::vector<std::shared_ptr<Submap>> order(submaps.begin(), submaps.end());
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
    if (a->isActive() != b->isActive()) return a->isActive();
    return a->id() < b->id();
  });

  const auto fresh_message = [this] {
    MeshUpdate m;
    m.map_epoch = epoch_;
    m.block_size = static_cast<float>(block_size_);
    return m;
  };
  MeshUpdate message = fresh_message();
  message.refresh_start = refresh_start;
  message.removed_submaps = std::move(removed);
  size_t message_bytes = 0, period_bytes = 0;
  uint64_t messages = 0, blocks = 0, bytes = 0;
  // `in_hand`: blocks taken from the pending sets that go into a later message.
  const auto emit = [&](size_t in_hand) {
    message.sequence = ++sequence_;
    message.blocks_pending = pending + in_hand;
    ++messages;
    blocks += message.blocks.size();
    bytes += message.payloadBytes();
    on_update_(message);
    message = fresh_message();
    message_bytes = 0;
  };

  for (const std::shared_ptr<Submap>& submap : order) {
    SubmapState& st = state_[submap->id()];
    for (auto it = st.pending.begin();
         it != st.pending.end() && period_bytes < config_.max_bytes_per_period;) {
      const uint64_t key = it->first;
      QuantizedBlockMesh mesh;
      // Entries without a mesh are of finished subvolumes, whose layers this thread owns.
      const bool ok = it->second ? (mesh = std::move(*it->second), true)
                                 : meshBlock(submap->layer(), key, &mesh);
      it = st.pending.erase(it);
      --pending;
      if (!ok) continue;
      const auto record = st.blocks.find(key);
      const bool receivers_hold = record != st.blocks.end() && record->second.has_surface;
      if (record != st.blocks.end()) {
        if (record->second.in_layer) {
          record->second.has_surface = !mesh.empty();
        } else {
          st.blocks.erase(record);
        }
      }
      if (mesh.empty() && !receivers_hold) continue;  // nothing to show, nothing to remove
      const size_t cost = mesh.payloadBytes() + kBlockOverheadBytes;
      if (!message.blocks.empty() && message_bytes + cost > config_.max_message_bytes) emit(1);
      message.blocks.push_back(MeshBlockUpdate{submap->id(), unpackGridIndex(key), std::move(mesh)});
      message_bytes += cost;
      period_bytes += cost;
    }
  }
  if (!message.blocks.empty() || !message.removed_submaps.empty() || message.refresh_start) {
    emit(0);
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.messages += messages;
  stats_.blocks_sent += blocks;
  stats_.bytes_sent += bytes;
  stats_.blocks_pending = pending;
}

SubvolumeList MeshStreamer::subvolumeList(
    const std::vector<std::shared_ptr<Submap>>& submaps) {
  SubvolumeList list;
  list.map_epoch = epoch_;
  list.block_size = static_cast<float>(block_size_);
  if (const std::shared_ptr<Submap> active = collection_->activeSubmap()) {
    list.active_submap = active->id();
  }
  for (const std::shared_ptr<Submap>& submap : submaps) {
    SubvolumeView view;
    view.id = submap->id();
    view.T_G_S = submap->T_G_M();
    view.active = submap->isActive();
    view.anchor_keyframe = submap->anchorKeyframe();
    view.num_blocks = submap->numBlocks();
    const auto it = state_.find(submap->id());
    if (it != state_.end()) {
      SubmapState& st = it->second;
      if (st.bounds_stale) {
        st.any_block = false;
        for (const auto& [key, record] : st.blocks) {
          if (!record.in_layer) continue;
          const BlockIndex index = unpackGridIndex(key);
          st.lo = st.any_block ? st.lo.cwiseMin(index) : index;
          st.hi = st.any_block ? st.hi.cwiseMax(index) : index;
          st.any_block = true;
        }
        st.bounds_stale = false;
      }
      if (st.any_block) {
        view.min_S = (st.lo.cast<double>() * block_size_).cast<float>();
        view.max_S = ((st.hi + BlockIndex::Ones()).cast<double>() * block_size_).cast<float>();
      }
    }
    list.subvolumes.push_back(view);
  }
  std::sort(list.subvolumes.begin(), list.subvolumes.end(),
            [](const SubvolumeView& a, const SubvolumeView& b) { return a.id < b.id; });
  return list;
}

void MeshStreamer::tick() {
  const Clock::time_point start = Clock::now();
  bool refresh = refresh_requested_.exchange(false, std::memory_order_acq_rel);
  const int64_t epoch = map_epoch_();
  if (first_tick_ || epoch != epoch_) {
    // A new map, or receivers holding a previous run's: everything again.
    state_.clear();
    epoch_ = epoch;
    first_tick_ = false;
    refresh = true;
  }
  if (config_.refresh_period_s > 0.0 && start >= next_refresh_) refresh = true;
  if (refresh) {
    next_refresh_ = start + std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(config_.refresh_period_s));
    for (auto& [id, st] : state_) {
      st.pending.clear();
      for (auto it = st.blocks.begin(); it != st.blocks.end();) {
        if (!it->second.in_layer) {
          st.blocks.erase(it++);
        } else {
          it->second.has_surface = false;
          ++it;
        }
      }
    }
  }

  const std::vector<std::shared_ptr<Submap>> submaps = collection_->submaps();
  absl::flat_hash_set<SubmapId> present;
  for (const auto& submap : submaps) present.insert(submap->id());
  std::vector<SubmapId> removed;
  for (auto it = state_.begin(); it != state_.end();) {
    if (present.contains(it->first)) {
      ++it;
    } else {
      removed.push_back(it->first);
      it = state_.erase(it);
    }
  }
  for (const std::shared_ptr<Submap>& submap : submaps) {
    SubmapState& st = state_[submap->id()];
    if (submap->isFinished()) {
      scanFinished(*submap, &st, refresh);
    } else {
      scanActive(*submap, &st, refresh);
    }
  }
  // The list first: a receiver knows where a new subvolume is before its blocks come.
  on_subvolumes_(subvolumeList(submaps));
  send(submaps, std::move(removed), refresh);

  period_ms_.add(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.periods;
  if (refresh) ++stats_.refreshes;
}

}  // namespace cblox
