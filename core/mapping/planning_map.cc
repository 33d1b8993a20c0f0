#include "core/mapping/planning_map.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

#include "core/common/text_format.h"
#include "core/common/thread_team.h"
#include "core/esdf/esdf_query.h"

namespace cblox {

PlanningMap::PlanningMap(const EsdfConfig& config)
    : config_(config), integrator_(config), active_integrator_(config) {}

namespace {

/// Moves a field's share `*counted` of the sum `*total` to `now`.
void recount(std::atomic<size_t>* total, size_t* counted, size_t now) {
  if (now >= *counted) {
    total->fetch_add(now - *counted, std::memory_order_relaxed);
  } else {
    total->fetch_sub(*counted - now, std::memory_order_relaxed);
  }
  *counted = now;
}

}  // namespace

size_t PlanningMap::projectedBytes(size_t tsdf_blocks, const LayerConfig& layer) const {
  // The working block and its snapshot's record; the voxels are shared.
  const size_t per_block =
      2 * sizeof(EsdfBlock) + static_cast<size_t>(layer.voxels_per_side) *
                                  static_cast<size_t>(layer.voxels_per_side) *
                                  static_cast<size_t>(layer.voxels_per_side) * sizeof(EsdfVoxel);
  const size_t blocks = field_blocks_.load(std::memory_order_relaxed);
  const size_t band = band_blocks_.load(std::memory_order_relaxed);
  // Band blocks per observed block as the computed fields have them (a sum of two relaxed
  // loads: an estimate while a field is being recounted).
  const double per_tsdf_block =
      blocks > band ? static_cast<double>(blocks) / static_cast<double>(blocks - band) : 1.0;
  const auto projected =
      static_cast<size_t>(static_cast<double>(tsdf_blocks) * per_tsdf_block) * per_block;
  return std::max(fieldBytes(), projected) + workingBytes();
}

std::shared_ptr<PlanningMap::Field> PlanningMap::fieldFor(const Submap& submap) {
  std::lock_guard<std::mutex> lock(index_mutex_);
  IndexEntry& entry = index_[submap.id()];
  if (!entry.field) {
    entry.id = submap.id();
    entry.field = std::make_shared<Field>(submap.layerConfig(), config_.max_distance_m);
    const Transformationd T_G_M = submap.T_G_M();
    entry.T_M_G = T_G_M.inverse();
    entry.R_G_M = T_G_M.rotationMatrix();
  }
  return entry.field;
}

void PlanningMap::updateField(const Submap& submap, const TsdfLayer& layer,
                              std::unique_lock<std::mutex>* layer_lock, EsdfIntegrator* integrator,
                              Field* field) {
  EsdfUpdateStats stats = integrator->stage(layer, &field->work);
  field->revision = submap.revision();  // stable while the layer is not written
  if (layer_lock != nullptr) layer_lock->unlock();
  integrator->finish(&field->work, &stats);
  (integrator == &active_integrator_ ? active_working_bytes_ : working_bytes_)
      .store(integrator->workingBytes(), std::memory_order_relaxed);
  std::shared_ptr<const EsdfLayer> published = field->work.snapshot();
  Eigen::AlignedBox3f box;
  const float block_size = layer.blockSize();
  size_t band_blocks = 0;
  for (const auto& [key, block] : published->blocks()) {
    const Eigen::Vector3f lo = block->index.cast<float>() * block_size;
    box.extend(lo);
    box.extend(lo + Eigen::Vector3f::Constant(block_size));
    if (block->isBand()) ++band_blocks;
  }
  {
    std::lock_guard<std::mutex> lock(field->bytes_mutex);
    const bool counted = !field->dropped;
    recount(&memory_bytes_, &field->counted_bytes,
            counted ? field->work.memoryBytes() + published->memoryBytes() : 0);
    recount(&field_blocks_, &field->counted_blocks, counted ? published->numBlocks() : 0);
    recount(&band_blocks_, &field->counted_band_blocks, counted ? band_blocks : 0);
  }
  updates_.fetch_add(1, std::memory_order_relaxed);
  if (stats.rebuilt) rebuilds_.fetch_add(1, std::memory_order_relaxed);
  std::lock_guard<std::mutex> lock(index_mutex_);
  const auto it = index_.find(submap.id());
  if (it != index_.end() && it->second.field.get() == field) {
    // The previous snapshot is freed here, or by the last query that still holds it.
    it->second.layer = std::move(published);
    it->second.box_M = box;
  }
}

void PlanningMap::refresh(const SubmapCollection& collection, Scope scope) {
  const std::vector<std::shared_ptr<Submap>> submaps = collection.submaps();
  std::set<SubmapId> present;
  for (const std::shared_ptr<Submap>& submap : submaps) present.insert(submap->id());
  std::vector<std::shared_ptr<Field>> dropped;
  {
    std::lock_guard<std::mutex> lock(index_mutex_);
    for (auto it = index_.begin(); it != index_.end();) {
      if (present.count(it->first) == 0) {
        dropped.push_back(it->second.field);
        it = index_.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (const std::shared_ptr<Field>& field : dropped) {
    // Queries that took its snapshot before the erase may still sample it; its bytes leave
    // now, and an update in hand on another thread publishes nowhere.
    std::lock_guard<std::mutex> lock(field->bytes_mutex);
    field->dropped = true;
    recount(&memory_bytes_, &field->counted_bytes, 0);
    recount(&field_blocks_, &field->counted_blocks, 0);
    recount(&band_blocks_, &field->counted_band_blocks, 0);
  }
  const auto start = std::chrono::steady_clock::now();
  bool updated = false;
  for (const std::shared_ptr<Submap>& submap : submaps) {
    if (scope == Scope::kFinished && submap->isActive()) continue;
    updated = refreshOne(*submap, &integrator_, /*owns_finished=*/true,
                         /*wait=*/scope == Scope::kAll) ||
              updated;
  }
  if (updated) recordRefresh(start);
  setPoses(collection.poseSnapshot());
}

bool PlanningMap::refreshOne(const Submap& submap, EsdfIntegrator* integrator, bool owns_finished,
                             bool wait) {
  const std::shared_ptr<Field> field = fieldFor(submap);
  std::unique_lock<std::mutex> update_lock(field->update_mutex, std::defer_lock);
  if (wait) {
    update_lock.lock();
  } else if (!update_lock.try_lock()) {
    return false;
  }
  if (field->work.numBlocks() > 0 && field->revision == submap.revision()) return false;
  if (submap.isActive()) {
    std::unique_lock<std::mutex> layer_lock = submap.lockLayer();
    if (submap.isActive()) {
      updateField(submap, submap.layer(), &layer_lock, integrator, field.get());
      return true;
    }
  }
  // Finished (possibly just now): its layer belongs to the thread that owns finished layers.
  if (!owns_finished) return false;
  updateField(submap, submap.layer(), nullptr, integrator, field.get());
  return true;
}

void PlanningMap::refreshActive(const SubmapCollection& collection) {
  const std::shared_ptr<Submap> active = collection.activeSubmap();
  if (!active) return;
  const auto start = std::chrono::steady_clock::now();
  bool updated = false;
  {
    std::lock_guard<std::mutex> lock(active_integrator_mutex_);
    updated = refreshOne(*active, &active_integrator_, /*owns_finished=*/false, /*wait=*/true);
  }
  if (updated) recordRefresh(start);
  setPoses(collection.poseSnapshot());
}

void PlanningMap::recordRefresh(std::chrono::steady_clock::time_point start) {
  refresh_ms_.add(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
}

void PlanningMap::setPoses(const std::vector<SubmapPose>& poses) {
  std::lock_guard<std::mutex> lock(index_mutex_);
  for (const SubmapPose& pose : poses) {
    const auto it = index_.find(pose.id);
    if (it == index_.end()) continue;
    it->second.T_M_G = pose.T_G_M.inverse();
    it->second.R_G_M = pose.T_G_M.rotationMatrix();
  }
}

std::vector<PlanningMap::IndexEntry> PlanningMap::indexSnapshot() const {
  std::vector<IndexEntry> entries;
  std::lock_guard<std::mutex> lock(index_mutex_);
  entries.reserve(index_.size());
  for (const auto& [id, entry] : index_) entries.push_back(entry);
  return entries;
}

Eigen::AlignedBox3d PlanningMap::boundsG() const {
  Eigen::AlignedBox3d bounds;  // empty
  for (const IndexEntry& entry : indexSnapshot()) {
    if (entry.box_M.isEmpty() || !entry.layer) continue;
    const Transformationd T_G_M = entry.T_M_G.inverse();
    const double block_size =
        static_cast<double>(entry.layer->voxelSize()) * entry.layer->voxelsPerSide();
    // Each block's centre, grown by its half diagonal: tight for a subvolume frame rotated
    // against G, where the box of the blocks' box would be much larger.
    const double reach = 0.5 * std::sqrt(3.0) * block_size;
    for (const auto& [key, block] : entry.layer->blocks()) {
      if (block->isBand()) continue;  // not observed
      const Eigen::Vector3d centre_M =
          (block->index.cast<double>() + Eigen::Vector3d::Constant(0.5)) * block_size;
      const Eigen::Vector3d centre_G = T_G_M * centre_M;
      bounds.extend(centre_G - Eigen::Vector3d::Constant(reach));
      bounds.extend(centre_G + Eigen::Vector3d::Constant(reach));
    }
  }
  return bounds;
}

DistanceAnswer PlanningMap::sample(const std::vector<IndexEntry>& index,
                                   const Eigen::Vector3d& p_G) const {
  DistanceAnswer answer;
  if (!p_G.allFinite()) return answer;
  // The smallest bound of the fields that cover the point without having observed it.
  DistanceSample bound;
  const IndexEntry* bound_entry = nullptr;
  float voxel = 0.0f;  // of the field that gave the answer
  for (const IndexEntry& entry : index) {
    const Eigen::Vector3f p_M = (entry.T_M_G * p_G).cast<float>();
    if (entry.box_M.isEmpty() || !entry.box_M.contains(p_M)) continue;
    const DistanceSample s = queryInterpolated(*entry.layer, p_M);
    if (s.state == VoxelState::kUnknown) {
      if (s.bound < bound.bound || (bound_entry == nullptr && !std::isnan(s.bound))) {
        bound = s;
        bound_entry = &entry;
      }
      continue;
    }
    // Occupied wins over free; among equals the nearest obstacle wins.
    const bool better =
        answer.state == VoxelState::kUnknown ||
        (s.state == VoxelState::kOccupied && answer.state != VoxelState::kOccupied) ||
        (s.state == answer.state && static_cast<double>(s.distance) < answer.distance);
    if (!better) continue;
    answer.state = s.state;
    answer.distance = s.distance;
    answer.has_gradient = s.has_gradient;
    answer.gradient = s.has_gradient
                          ? Eigen::Vector3d(entry.R_G_M * s.gradient.cast<double>())
                          : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    answer.submap = static_cast<int64_t>(entry.id);
    voxel = entry.layer->voxelSize();
  }
  if (answer.state == VoxelState::kFree && bound_entry != nullptr &&
      static_cast<double>(bound.bound) < answer.distance) {
    answer.distance = bound.bound;
    answer.has_gradient = bound.has_gradient;
    answer.gradient = bound.has_gradient
                          ? Eigen::Vector3d(bound_entry->R_G_M * bound.gradient.cast<double>())
                          : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    answer.submap = static_cast<int64_t>(bound_entry->id);
    voxel = bound_entry->layer->voxelSize();
  }
  if (answer.state == VoxelState::kFree) {
    double slope = 1.0;
    answer.distance =
        lowerBesideSurface(answer.distance, static_cast<double>(voxel),
                           static_cast<double>(config_.surface_margin_voxels), &slope);
    if (answer.has_gradient) answer.gradient *= slope;
  }
  return answer;
}

DistanceAnswer PlanningMap::query(const Eigen::Vector3d& p_G) const {
  return sample(indexSnapshot(), p_G);
}

void PlanningMap::queryBatch(std::span<const Eigen::Vector3d> points_G,
                             std::vector<DistanceAnswer>* answers, int num_threads) const {
  const std::vector<IndexEntry> index = indexSnapshot();
  answers->resize(points_G.size());
  const size_t n = points_G.size();
  const size_t threads =
      std::clamp<size_t>(n / kMinPointsPerThread, 1, static_cast<size_t>(std::max(num_threads, 1)));
  // sample() only reads `index` and the immutable snapshots it holds.
  runThreadTeam(static_cast<int>(threads), [&](int id) {
    const size_t begin = n * static_cast<size_t>(id) / threads;
    const size_t end = n * (static_cast<size_t>(id) + 1) / threads;
    for (size_t i = begin; i < end; ++i) (*answers)[i] = sample(index, points_G[i]);
  });
}

bool PlanningMap::localGrid(const Eigen::Vector3d& min_G, const Eigen::Vector3d& max_G,
                            double resolution, LocalGrid* grid, std::string* error) const {
  if (!min_G.allFinite() || !max_G.allFinite()) {
    *error = "the box's corners must be finite";
    return false;
  }
  if (!((max_G - min_G).minCoeff() > 0.0)) {
    *error = "the box's maximum corner must be above its minimum on every axis";
    return false;
  }
  if (!std::isfinite(resolution) || !(resolution > 0.0)) {
    *error = "the resolution must be finite and > 0";
    return false;
  }
  // Counted in double before any integer conversion, so that a huge box cannot overflow.
  // A side within 1e-6 of a whole number of cells is that many: [0.2, 0.8] at 0.1 is 6
  // cells, not the 7 that rounding 6.000000000000001 up would make.
  const Eigen::Vector3d cells =
      ((max_G - min_G) / resolution - Eigen::Vector3d::Constant(1e-6)).array().ceil().max(1.0);
  if (cells.prod() > static_cast<double>(kMaxGridCells)) {
    *error = "the box has " + significant(cells.prod(), 3) +
             " cells at this resolution, more than " + std::to_string(kMaxGridCells);
    return false;
  }
  grid->origin = min_G;
  grid->resolution = resolution;
  grid->size = cells.cast<int>();
  const size_t n = static_cast<size_t>(cells.prod());
  grid->state.assign(n, VoxelState::kUnknown);
  grid->distance.assign(n, std::numeric_limits<float>::quiet_NaN());
  const std::vector<IndexEntry> index = indexSnapshot();
  for (int k = 0; k < grid->size.z(); ++k) {
    for (int j = 0; j < grid->size.y(); ++j) {
      for (int i = 0; i < grid->size.x(); ++i) {
        const DistanceAnswer a = sample(index, grid->cellCenter(i, j, k));
        const size_t c = grid->index(i, j, k);
        grid->state[c] = a.state;
        grid->distance[c] = static_cast<float>(a.distance);
      }
    }
  }
  return true;
}

PlanningMapStats PlanningMap::stats() const {
  PlanningMapStats stats;
  {
    std::lock_guard<std::mutex> lock(index_mutex_);
    stats.fields = index_.size();
  }
  // Counted as each field publishes (updateField), as its bytes are.
  stats.blocks = field_blocks_.load(std::memory_order_relaxed);
  stats.band_blocks = band_blocks_.load(std::memory_order_relaxed);
  stats.memory_bytes = memoryBytes();
  stats.updates = updates_.load(std::memory_order_relaxed);
  stats.rebuilds = rebuilds_.load(std::memory_order_relaxed);
  return stats;
}

}  // namespace cblox
