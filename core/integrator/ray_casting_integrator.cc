#include "core/integrator/ray_casting_integrator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <stdexcept>

#include "core/common/thread_team.h"
#include "core/integrator/deadline.h"
#include "core/integrator/even_coverage_order.h"
#include "core/integrator/grid_ray_traversal.h"
#include "core/integrator/ray_point_screen.h"
#include "core/integrator/tsdf_voxel_update.h"

namespace cblox {
namespace {

constexpr uint64_t kNoBlock = std::numeric_limits<uint64_t>::max();
// Parked rays handed to a thread at a time when they resume.
constexpr size_t kParkedPerClaim = 64;
// The start-voxel set clusters 4x4x4 start cells (6 member bits).
constexpr int kStartClusterLog2 = 2;

}  // namespace

struct RayCastingIntegrator::ParkedRay {
  uint32_t index = 0;     // point index in the cloud
  int collisions = 0;     // consecutive re-visited voxels so far (fast mode)
  GridRayTraversal walk;  // positioned at the next voxel to update
};

struct RayCastingIntegrator::ThreadState {
  IntegrationStats stats;
  std::vector<ParkedRay> parked;
  std::vector<uint64_t> missing_blocks;
};

struct RayCastingIntegrator::Frame {
  const Eigen::Matrix3f R_G_C;  // rotation as a matrix: 15 flops per point, not 30
  const PointCloud& cloud_C;
  Eigen::Vector3f origin_G;
  Deadline deadline;
  TsdfVoxelUpdater updater;
  uint64_t epoch;  // this call's Block::markVisited epoch
  // Range, finiteness and grid checks of the points, and their start cells.
  RayPointScreen screen;
  std::atomic<size_t> cursor{0};
  std::atomic<bool> out_of_time{false};

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
    : mode_(mode), config_(config), layer_(layer) {
  if (layer == nullptr) throw std::invalid_argument("RayCastingIntegrator: layer is null");
  const std::string error = config.validate(layer->voxelSize());
  if (!error.empty()) throw std::invalid_argument("IntegratorConfig: " + error);
  if (mode_ == Mode::kFast) {
    start_voxel_set_ = std::make_unique<ApproxHashSet>(config.approx_set_log2_buckets);
    if (config.visited_voxel_set == VisitedVoxelSet::kApproxHashSet) {
      visited_voxel_set_ = std::make_unique<ApproxHashSet>(config.approx_set_log2_buckets);
    }
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
  const float min_length = std::max(config_.min_ray_length_m, 1e-6f);
  const RayPointScreen::Frame screen_frame{
      T_G_C.rotationMatrix(), T_G_C.translation(), min_length * min_length,
      config_.max_ray_length_m * config_.max_ray_length_m,
      // |coordinate| bound keeping every ray inside the packable grid
      (kGridIndexMax - 2) * layer_->voxelSize() - config_.truncation_distance_m,
      layer_->voxelSizeInv() * config_.start_voxel_subsampling_factor};
  Frame frame{screen_frame.R_G_C,
              cloud_C,
              T_G_C.translation(),
              Deadline(fast ? config_.max_integration_time_s : 0.0),
              TsdfVoxelUpdater(config_, layer_->voxelSize()),
              layer_->nextIntegrationEpoch(),
              RayPointScreen(screen_frame, config_.vectorized)};
  const size_t num_chunks = (cloud_C.size() + kPointsPerChunk - 1) / kPointsPerChunk;
  if (chunk_order_.size() != num_chunks) {
    chunk_order_ = evenCoverageOrder(static_cast<uint32_t>(num_chunks));
  }
  if (fast) {
    start_voxel_set_->clear();
    if (visited_voxel_set_) visited_voxel_set_->clear();
  }
  const int num_threads = config_.num_threads;
  std::vector<ThreadState> states(static_cast<size_t>(num_threads));

  // Main pass: every point in chunk order; rays that reach a missing block are parked.
  runThreadTeam(num_threads, [&](int id) { castChunks(frame, &states[static_cast<size_t>(id)]); });

  // Allocate what parked rays need, single-threaded, and resume them; repeat.
  std::vector<BlockIndex> new_blocks;
  std::vector<ParkedRay> parked;
  std::vector<uint64_t> missing;
  size_t rays_cut_by_budget = 0;
  for (;;) {
    parked.clear();
    missing.clear();
    for (ThreadState& state : states) {
      parked.insert(parked.end(), state.parked.begin(), state.parked.end());
      missing.insert(missing.end(), state.missing_blocks.begin(), state.missing_blocks.end());
      state.parked.clear();
      state.missing_blocks.clear();
    }
    if (parked.empty()) break;
    if (fast && frame.outOfTime()) {
      rays_cut_by_budget += parked.size();
      break;
    }
    std::sort(missing.begin(), missing.end());
    missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
    for (const uint64_t key : missing) {
      bool newly_allocated = false;
      const BlockIndex index = unpackGridIndex(key);
      layer_->allocateBlock(index, &newly_allocated);
      if (newly_allocated) new_blocks.push_back(index);
    }
    frame.cursor.store(0);
    runThreadTeam(num_threads,
                  [&](int id) { resumeParked(frame, parked, &states[static_cast<size_t>(id)]); });
  }

  IntegrationStats stats;
  for (const ThreadState& state : states) stats += state.stats;
  for (const BlockIndex& index : new_blocks) {
    if (layer_->getBlock(index)->updated()) {
      ++stats.blocks_allocated;
    } else {
      layer_->removeBlock(index);
    }
  }
  stats.points_in = cloud_C.size();
  stats.rays_cut_by_budget += rays_cut_by_budget;
  stats.budget_exhausted = frame.out_of_time.load();
  stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return stats;
}

// A point that passed the range checks, with its start-voxel set key (fast mode).
struct RayCastingIntegrator::StartCell {
  uint32_t index = 0;
  uint64_t cell = 0;     // packed start-cell index (packGridIndex)
  uint64_t cluster = 0;  // key of its 4x4x4 cluster of start cells
  uint32_t member = 0;   // the cell inside its cluster

  // Cluster and member straight from the packed fields: each field is the index plus
  // 2^20, a multiple of 4, so dropping its two low bits is the floor division by 4.
  void splitCell() {
    constexpr uint64_t kField = (uint64_t{1} << kGridIndexBits) - 1;
    constexpr uint64_t kLow = (uint64_t{1} << kStartClusterLog2) - 1;
    const uint64_t x = cell & kField, y = (cell >> kGridIndexBits) & kField,
                   z = cell >> (2 * kGridIndexBits);
    cluster = (x >> kStartClusterLog2) | ((y >> kStartClusterLog2) << kGridIndexBits) |
              ((z >> kStartClusterLog2) << (2 * kGridIndexBits));
    member = static_cast<uint32_t>((x & kLow) | ((y & kLow) << kStartClusterLog2) |
                                   ((z & kLow) << (2 * kStartClusterLog2)));
  }
};

void RayCastingIntegrator::castChunks(Frame& frame, ThreadState* state) {
  const bool fast = mode_ == Mode::kFast;
  const size_t n = frame.cloud_C.size();
  IntegrationStats& stats = state->stats;
  ScreenedPoint screened[kPointsPerChunk];
  StartCell candidates[kPointsPerChunk];
  for (size_t c = frame.cursor.fetch_add(1, std::memory_order_relaxed); c < chunk_order_.size();
       c = frame.cursor.fetch_add(1, std::memory_order_relaxed)) {
    const size_t begin = static_cast<size_t>(chunk_order_[c]) * kPointsPerChunk;
    const size_t end = std::min(n, begin + kPointsPerChunk);
    if (fast && frame.outOfTime()) {
      stats.points_not_reached += end - begin;
      continue;
    }
    // First screen the whole chunk and prefetch the start-set buckets, so that the
    // set's cache misses overlap; then insert and cast.
    const size_t accepted = frame.screen.screen(
        &frame.cloud_C.points[begin], static_cast<uint32_t>(begin), end - begin, screened, &stats);
    size_t count = 0;
    uint64_t last_cell = kNoBlock;  // consecutive points often share a start cell
    for (size_t k = 0; k < accepted; ++k) {
      StartCell& candidate = candidates[count];
      candidate.index = screened[k].index;
      if (fast) {
        candidate.cell = screened[k].cell;
        if (candidate.cell == last_cell) {  // what the set would answer, without a lookup
          ++stats.points_subsampled;
          continue;
        }
        last_cell = candidate.cell;
        candidate.splitCell();
        start_voxel_set_->prefetchInCluster(candidate.cluster, candidate.member,
                                            3 * kStartClusterLog2);
      }
      ++count;
    }
    for (size_t k = 0; k < count; ++k) {
      const StartCell& candidate = candidates[k];
      if (fast && !start_voxel_set_->insertInCluster(candidate.cluster, candidate.member,
                                                     3 * kStartClusterLog2)) {
        ++stats.points_subsampled;
        continue;
      }
      ++stats.rays_cast;
      walkRay(frame, candidate.index, nullptr, state);
    }
  }
}

void RayCastingIntegrator::resumeParked(Frame& frame, const std::vector<ParkedRay>& parked,
                                        ThreadState* state) {
  const bool fast = mode_ == Mode::kFast;
  for (size_t begin = frame.cursor.fetch_add(kParkedPerClaim); begin < parked.size();
       begin = frame.cursor.fetch_add(kParkedPerClaim)) {
    const size_t end = std::min(parked.size(), begin + kParkedPerClaim);
    if (fast && frame.outOfTime()) {
      state->stats.rays_cut_by_budget += end - begin;
      continue;
    }
    for (size_t i = begin; i < end; ++i) walkRay(frame, parked[i].index, &parked[i], state);
  }
}

void RayCastingIntegrator::walkRay(Frame& frame, uint32_t index, const ParkedRay* resume,
                                   ThreadState* state) {
  const bool fast = mode_ == Mode::kFast;
  const float voxel_size = layer_->voxelSize();
  const int vps_log2 = layer_->voxelsPerSideLog2();
  const int member_bits = 3 * vps_log2;
  const Eigen::Vector3f& point_C = frame.cloud_C.points[index];
  const float length = point_C.norm();
  const Eigen::Vector3f point_G = frame.R_G_C * point_C + frame.origin_G;
  const Eigen::Vector3f unit_G = (point_G - frame.origin_G) / length;
  // A new ray runs from one truncation behind the point towards the sensor (or to one
  // truncation in front of the point without voxel carving); a parked one goes on.
  ParkedRay ray = resume != nullptr ? *resume : [&] {
    const float truncation = config_.truncation_distance_m;
    const Eigen::Vector3f far_G = point_G + unit_G * truncation;
    const Eigen::Vector3f near_G = config_.voxel_carving_enabled
                                       ? frame.origin_G
                                       : Eigen::Vector3f(point_G - unit_G * truncation);
    const float voxel_size_inv = layer_->voxelSizeInv();
    return ParkedRay{index, 0, GridRayTraversal(far_G * voxel_size_inv, near_G * voxel_size_inv)};
  }();
  // The distance along the ray of voxel centre c is length - (c - origin).unit.
  const float sdf_offset = length + frame.origin_G.dot(unit_G);
  const float weight = frame.updater.measurementWeight(point_C.z() > 0.0f ? point_C.z() : length);
  const Color color = frame.cloud_C.hasColors() ? frame.cloud_C.colors[index] : Color{};
  IntegrationStats& stats = state->stats;

  // Inside a block the walk steps by index arithmetic: the voxel's linear index and its
  // distance along the ray change by a constant per axis step. Both are recomputed exactly
  // whenever the ray enters a block, so rounding cannot accumulate beyond one block.
  GridRayTraversal& walk = ray.walk;
  const int vps = 1 << vps_log2;
  const int linear_stride[3] = {1, vps, vps * vps};
  const float sdf_step[3] = {voxel_size * unit_G.x(), voxel_size * unit_G.y(),
                             voxel_size * unit_G.z()};
  Block* block = nullptr;
  bool block_touched = false;
  GridIndex local;
  int linear = 0;
  float sdf = 0.0f;
  uint64_t block_key = kNoBlock;
  // Enters the block of walk.cell(): false when it is missing (the ray is parked).
  auto enterBlock = [&]() {
    BlockIndex block_index;
    splitGlobalVoxelIndex(walk.cell(), vps_log2, &block_index, &local);
    block_key = packGridIndex(block_index);
    block = layer_->getBlockByKey(block_key);
    if (block == nullptr) {
      state->parked.push_back(ray);
      state->missing_blocks.push_back(block_key);
      return false;
    }
    block->lock().lock();
    block_touched = false;
    linear = block->linearIndex(local);
    const Eigen::Vector3f center =
        (walk.cell().cast<float>() + Eigen::Vector3f::Constant(0.5f)) * voxel_size;
    sdf = sdf_offset - center.dot(unit_G);
    return true;
  };
  auto leaveBlock = [&]() {
    if (block_touched) block->setUpdated(true);
    block->lock().unlock();
  };
  if (!enterBlock()) return;
  for (;;) {
    // Collisions count everywhere along the ray, as in the paper. Counting them only
    // outside the truncation band was tried: 2.5x the voxel updates for the same median
    // surface error (BENCHMARKS.md, "Accuracy: against exact ground truth").
    if (fast) {
      const bool fresh = visited_voxel_set_
                             ? visited_voxel_set_->insertInCluster(
                                   block_key, static_cast<uint32_t>(linear), member_bits)
                             : block->markVisited(linear, frame.epoch);
      if (fresh) {
        ray.collisions = 0;
      } else if (++ray.collisions > config_.max_consecutive_ray_collisions) {
        ++stats.rays_stopped_early;
        break;
      }
    }
    if (frame.updater.update(sdf, weight, color, &block->voxel(linear))) {
      ++stats.voxel_updates;
      block_touched = true;
    }
    if (!walk.advance()) break;
    const int axis = walk.lastAxis();
    const int step = walk.lastStep();
    local[axis] += step;
    if (static_cast<unsigned>(local[axis]) < static_cast<unsigned>(vps)) {
      linear += step * linear_stride[axis];
      sdf -= static_cast<float>(step) * sdf_step[axis];
    } else {
      leaveBlock();
      if (!enterBlock()) return;
    }
  }
  leaveBlock();
}

}  // namespace cblox
