#include "core/integrator/ray_casting_integrator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <stdexcept>

#include "core/integrator/deadline.h"
#include "core/integrator/even_coverage_order.h"
#include "core/integrator/grid_ray_traversal.h"
#include "core/integrator/thread_team.h"
#include "core/integrator/tsdf_voxel_update.h"

namespace cblox {
namespace {

// Points handed to a thread at a time; the budget is checked once per chunk.
constexpr size_t kChunkSize = 64;
// Block-level dedup set: blocks crossed by one frame are in the thousands.
constexpr int kBlockSetLog2Buckets = 16;
constexpr uint64_t kNoBlock = std::numeric_limits<uint64_t>::max();

}  // namespace

struct RayCastingIntegrator::ThreadState {
  IntegrationStats stats;
  std::vector<uint64_t> new_block_keys;
};

struct RayCastingIntegrator::Frame {
  const Transformation& T_G_C;
  const PointCloud& cloud_C;
  Eigen::Vector3f origin_G;
  Deadline deadline;
  TsdfVoxelUpdater updater;
  std::atomic<size_t> cursor{0};
  std::atomic<bool> out_of_time{false};

  // Claims the next chunk of the point order; false when none is left.
  bool claim(size_t* begin, size_t* end) {
    *begin = cursor.fetch_add(kChunkSize, std::memory_order_relaxed);
    if (*begin >= cloud_C.size()) return false;
    *end = std::min(*begin + kChunkSize, cloud_C.size());
    return true;
  }
  // True when the budget is spent (sticky across threads).
  bool outOfTime() {
    if (out_of_time.load(std::memory_order_relaxed)) return true;
    if (!deadline.expired()) return false;
    out_of_time.store(true, std::memory_order_relaxed);
    return true;
  }
};

RayCastingIntegrator::RayCastingIntegrator(Mode mode, const IntegratorConfig& config,
                                           TsdfLayer* layer)
    : mode_(mode), config_(config), layer_(layer), block_set_(kBlockSetLog2Buckets) {
  if (layer == nullptr) throw std::invalid_argument("RayCastingIntegrator: layer is null");
  const std::string error = config.validate(layer->voxelSize());
  if (!error.empty()) throw std::invalid_argument("IntegratorConfig: " + error);
  if (mode_ == Mode::kFast) {
    start_voxel_set_ = std::make_unique<ApproxHashSet>(config.approx_set_log2_buckets);
    visited_voxel_set_ = std::make_unique<ApproxHashSet>(config.approx_set_log2_buckets);
  }
}

RayCastingIntegrator::~RayCastingIntegrator() = default;

IntegrationStats RayCastingIntegrator::integratePointCloud(const Transformation& T_G_C,
                                                           const PointCloud& cloud_C) {
  const auto start_time = std::chrono::steady_clock::now();
  if (cloud_C.size() > std::numeric_limits<uint32_t>::max()) {
    throw std::invalid_argument("RayCastingIntegrator: point cloud too large");
  }
  if (cloud_C.hasColors() && cloud_C.colors.size() != cloud_C.points.size()) {
    throw std::invalid_argument("RayCastingIntegrator: colours and points differ in size");
  }
  const bool fast = mode_ == Mode::kFast;
  Frame frame{T_G_C,
              cloud_C,
              T_G_C.translation(),
              Deadline(fast ? config_.max_integration_time_s : 0.0),
              TsdfVoxelUpdater(config_, layer_->voxelSize())};

  const size_t n = cloud_C.size();
  if (order_.size() != n) order_ = evenCoverageOrder(static_cast<uint32_t>(n));
  accepted_.assign(n, 0);
  block_set_.clear();
  if (fast) {
    start_voxel_set_->clear();
    visited_voxel_set_->clear();
  }

  const int num_threads = config_.num_threads;
  std::vector<ThreadState> states(static_cast<size_t>(num_threads));

  // Phase 1: accept points and collect the blocks their rays cross.
  runThreadTeam(num_threads, [&](int id) {
    acceptPointsAndCollectBlocks(frame, &states[static_cast<size_t>(id)]);
  });

  // Allocation, single-threaded: the hash map is never written concurrently.
  std::vector<BlockIndex> new_blocks;
  for (const ThreadState& state : states) {
    for (const uint64_t key : state.new_block_keys) {
      bool newly_allocated = false;
      const BlockIndex index = unpackGridIndex(key);
      layer_->allocateBlock(index, &newly_allocated);
      if (newly_allocated) new_blocks.push_back(index);
    }
  }

  // Phase 2: walk the accepted rays voxel by voxel.
  frame.cursor.store(0);
  runThreadTeam(num_threads,
                [&](int id) { castRays(frame, &states[static_cast<size_t>(id)]); });

  IntegrationStats stats;
  for (const ThreadState& state : states) stats += state.stats;
  for (const BlockIndex& index : new_blocks) {
    if (layer_->getBlock(index)->updated()) {
      ++stats.blocks_allocated;
    } else {
      layer_->removeBlock(index);
    }
  }
  stats.points_in = n;
  stats.budget_exhausted = frame.out_of_time.load();
  stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return stats;
}

void RayCastingIntegrator::acceptPointsAndCollectBlocks(Frame& frame, ThreadState* state) {
  const bool fast = mode_ == Mode::kFast;
  const float truncation = config_.truncation_distance_m;
  const float block_size_inv = layer_->blockSizeInv();
  const float start_cell_inv = layer_->voxelSizeInv() * config_.start_voxel_subsampling_factor;
  const float min_length = std::max(config_.min_ray_length_m, 1e-6f);
  IntegrationStats& stats = state->stats;

  size_t begin = 0, end = 0;
  while (frame.claim(&begin, &end)) {
    if (fast && frame.outOfTime()) {
      stats.points_not_reached += end - begin;
      continue;
    }
    for (size_t i = begin; i < end; ++i) {
      const uint32_t index = order_[i];
      const Eigen::Vector3f& point_C = frame.cloud_C.points[index];
      if (!point_C.allFinite()) {
        ++stats.points_invalid;
        continue;
      }
      const float length = point_C.norm();
      if (length < min_length || length > config_.max_ray_length_m) {
        ++stats.points_out_of_range;
        continue;
      }
      const Eigen::Vector3f point_G = frame.T_G_C * point_C;
      const Eigen::Vector3f unit_G = (point_G - frame.origin_G) / length;
      const Eigen::Vector3f far_G = point_G + unit_G * truncation;
      const Eigen::Vector3f near_G =
          config_.voxel_carving_enabled ? frame.origin_G : Eigen::Vector3f(point_G - unit_G * truncation);
      // Rays whose ends fall outside the packable grid (absurd poses) are rejected whole.
      if (!gridIndexInRange(gridIndexFromPoint(far_G, layer_->voxelSizeInv())) ||
          !gridIndexInRange(gridIndexFromPoint(near_G, layer_->voxelSizeInv()))) {
        ++stats.points_invalid;
        continue;
      }
      if (fast &&
          !start_voxel_set_->insert(packGridIndex(gridIndexFromPoint(point_G, start_cell_inv)))) {
        ++stats.points_subsampled;
        continue;
      }
      accepted_[index] = 1;
      for (GridRayTraversal walk(far_G * block_size_inv, near_G * block_size_inv);;) {
        const uint64_t key = packGridIndex(walk.cell());
        if (block_set_.insert(key)) state->new_block_keys.push_back(key);
        if (!walk.advance()) break;
      }
    }
  }
}

void RayCastingIntegrator::castRays(Frame& frame, ThreadState* state) {
  const bool fast = mode_ == Mode::kFast;
  const float truncation = config_.truncation_distance_m;
  const float voxel_size = layer_->voxelSize();
  const float voxel_size_inv = layer_->voxelSizeInv();
  const int vps_log2 = layer_->voxelsPerSideLog2();
  const int max_collisions = config_.max_consecutive_ray_collisions;
  const bool has_colors = frame.cloud_C.hasColors();
  IntegrationStats& stats = state->stats;

  size_t begin = 0, end = 0;
  while (frame.claim(&begin, &end)) {
    if (fast && frame.outOfTime()) {
      for (size_t i = begin; i < end; ++i) stats.points_not_reached += accepted_[order_[i]];
      continue;
    }
    for (size_t i = begin; i < end; ++i) {
      const uint32_t index = order_[i];
      if (!accepted_[index]) continue;
      ++stats.rays_cast;
      const Eigen::Vector3f& point_C = frame.cloud_C.points[index];
      const float length = point_C.norm();
      const Eigen::Vector3f point_G = frame.T_G_C * point_C;
      const Eigen::Vector3f unit_G = (point_G - frame.origin_G) / length;
      const Eigen::Vector3f far_G = point_G + unit_G * truncation;
      const Eigen::Vector3f near_G =
          config_.voxel_carving_enabled ? frame.origin_G : Eigen::Vector3f(point_G - unit_G * truncation);
      const float weight =
          frame.updater.measurementWeight(point_C.z() > 0.0f ? point_C.z() : length);
      const Color color = has_colors ? frame.cloud_C.colors[index] : Color{};

      Block* block = nullptr;
      uint64_t block_key = kNoBlock;
      bool block_touched = false;
      int collisions = 0;
      for (GridRayTraversal walk(far_G * voxel_size_inv, near_G * voxel_size_inv);;) {
        const GlobalVoxelIndex& global = walk.cell();
        BlockIndex block_index;
        GridIndex local;
        splitGlobalVoxelIndex(global, vps_log2, &block_index, &local);
        const uint64_t key = packGridIndex(block_index);
        if (key != block_key) {
          if (block != nullptr) {
            if (block_touched) block->setUpdated(true);
            block->lock().unlock();
          }
          block = layer_->getBlockByKey(key);
          block_key = key;
          block_touched = false;
          if (block != nullptr) block->lock().lock();
        }
        if (fast) {
          if (visited_voxel_set_->insert(packGridIndex(global))) {
            collisions = 0;
          } else if (++collisions > max_collisions) {
            ++stats.rays_stopped_early;
            break;
          }
        }
        if (block != nullptr) {
          const Eigen::Vector3f center =
              (global.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * voxel_size;
          const float sdf = length - (center - frame.origin_G).dot(unit_G);
          if (frame.updater.update(sdf, weight, color, &block->voxel(local))) {
            ++stats.voxel_updates;
            block_touched = true;
          }
        }
        if (!walk.advance()) break;
      }
      if (block != nullptr) {
        if (block_touched) block->setUpdated(true);
        block->lock().unlock();
      }
    }
  }
}

}  // namespace cblox
