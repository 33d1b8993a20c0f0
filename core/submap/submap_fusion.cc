#include "core/submap/submap_fusion.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <absl/container/flat_hash_set.h>

#include "core/common/thread_team.h"
#include "core/tsdf/block_index.h"

namespace cblox {

std::string SubmapFusionConfig::validate() const {
  std::ostringstream error;
  if (!std::isfinite(min_weight) || min_weight <= 0.0f) {
    error << "min_weight must be finite and > 0, got " << min_weight;
  } else if (!std::isfinite(max_weight) || max_weight < min_weight) {
    error << "max_weight must be finite and >= min_weight (" << min_weight << "), got "
          << max_weight;
  } else if (!(min_sample_coverage > 0.0f && min_sample_coverage <= 1.0f)) {
    error << "min_sample_coverage must be in (0, 1], got " << min_sample_coverage;
  } else if (num_threads < 1 || num_threads > 64) {
    error << "num_threads must be in [1, 64], got " << num_threads;
  }
  return error.str();
}

namespace {

// Trilinear sampling of the source layer at continuous voxel coordinates q (voxel i has its
// centre at q = i), as documented at fuseLayers. One instance per thread.
class SourceSampler {
 public:
  SourceSampler(const TsdfLayer& layer, float min_weight, float min_coverage)
      : layer_(layer),
        min_weight_(min_weight),
        min_coverage_(min_coverage),
        log2_(layer.voxelsPerSideLog2()),
        mask_(layer.voxelsPerSide() - 1) {}

  // *complete (optional): every needed corner was observed (not a rim sample).
  bool sample(const Eigen::Vector3f& q, float* distance, float* weight, Eigen::Vector3f* color,
              bool* complete_out = nullptr) {
    GlobalVoxelIndex base(fastFloor(q.x()), fastFloor(q.y()), fastFloor(q.z()));
    Eigen::Vector3f f = q - base.cast<float>();
    // q just below an integer can round to f == 1: the same point as base + 1 with f == 0.
    for (int axis = 0; axis < 3; ++axis) {
      if (f[axis] >= 1.0f) {
        base[axis] += 1;
        f[axis] = 0.0f;
      }
    }
    const BlockIndex block_index(base.x() >> log2_, base.y() >> log2_, base.z() >> log2_);
    const GridIndex local(base.x() & mask_, base.y() & mask_, base.z() & mask_);
    const Block* base_block = block(block_index);
    const bool one_block =
        base_block != nullptr && local.x() < mask_ && local.y() < mask_ && local.z() < mask_;

    float sum_distance = 0.0f, sum_weight = 0.0f, coverage = 0.0f;
    Eigen::Vector3f sum_color = Eigen::Vector3f::Zero();
    bool complete = true;
    for (int corner = 0; corner < 8; ++corner) {
      const int ox = corner & 1, oy = (corner >> 1) & 1, oz = (corner >> 2) & 1;
      const float cx = ox ? f.x() : 1.0f - f.x();
      const float cy = oy ? f.y() : 1.0f - f.y();
      const float cz = oz ? f.z() : 1.0f - f.z();
      if (cx == 0.0f || cy == 0.0f || cz == 0.0f) continue;  // not needed, not read
      const TsdfVoxel* voxel = nullptr;
      if (one_block) {
        voxel = &base_block->voxel(GridIndex(local.x() + ox, local.y() + oy, local.z() + oz));
      } else {
        const GlobalVoxelIndex g(base.x() + ox, base.y() + oy, base.z() + oz);
        const Block* b = block(BlockIndex(g.x() >> log2_, g.y() >> log2_, g.z() >> log2_));
        if (b != nullptr) voxel = &b->voxel(GridIndex(g.x() & mask_, g.y() & mask_, g.z() & mask_));
      }
      if (voxel == nullptr || !(voxel->weight >= min_weight_)) {
        complete = false;
        continue;
      }
      const float c = cx * cy * cz;
      coverage += c;
      sum_distance += c * voxel->distance;
      sum_weight += c * voxel->weight;
      sum_color += c * Eigen::Vector3f(voxel->color.r, voxel->color.g, voxel->color.b);
    }
    if (complete_out != nullptr) *complete_out = complete;
    if (complete) {
      *distance = sum_distance;
      *weight = sum_weight;
      *color = sum_color;
      return true;
    }
    if (!(coverage >= min_coverage_) || coverage <= 0.0f) return false;
    *distance = sum_distance / coverage;
    *weight = sum_weight;
    *color = sum_color / coverage;
    return true;
  }

 private:
  // Block lookup with a one-entry cache (consecutive target voxels mostly sample one block).
  const Block* block(const BlockIndex& index) {
    if (!cache_valid_ || index != cached_index_) {
      cached_block_ = layer_.getBlock(index);
      cached_index_ = index;
      cache_valid_ = true;
    }
    return cached_block_;
  }

  const TsdfLayer& layer_;
  float min_weight_;
  float min_coverage_;
  int log2_;
  int mask_;
  bool cache_valid_ = false;
  BlockIndex cached_index_ = BlockIndex::Zero();
  const Block* cached_block_ = nullptr;
};

uint8_t roundChannel(float value) {
  return static_cast<uint8_t>(std::lround(std::clamp(value, 0.0f, 255.0f)));
}

// Target voxels are visited in cubic cells of this many voxels a side; a cell whose samples
// can read no observed source block is skipped whole.
constexpr int kFusionCellVoxels = 4;

// Whether a cell of target voxels can read an observed source block. The samples of the
// cell's voxel centres g (q = A g + c, affine) lie in the box q(centre) +- |A| h (h: the
// cell's half extent, |A| element-wise: the bounding box of the cube's image); every corner a
// sample reads lies in [floor(q_min), floor(q_max) + 1]. The box is widened
// by a margin far above the float rounding of q as fuseLayers steps it (a few ulps of |q|),
// so a skipped cell is one whose every sample would fail: skipping changes no voxel.
struct CellReach {
  const Eigen::Matrix3d& A;
  const Eigen::Vector3d& c;
  int source_log2;
  const absl::flat_hash_set<uint64_t>* observed;

  bool mayReachObservedSource(const GlobalVoxelIndex& first, int cell) const {
    constexpr double kLimit = 1 << 30;  // beyond: no shortcut, every voxel is sampled
    const double h = 0.5 * (cell - 1);
    const Eigen::Vector3d centre = A * (first.cast<double>() + Eigen::Vector3d::Constant(h)) + c;
    // Inside a dense source the block at the cell's centre decides at once.
    if (centre.cwiseAbs().maxCoeff() < kLimit) {
      const BlockIndex index(static_cast<int>(std::floor(centre.x())) >> source_log2,
                             static_cast<int>(std::floor(centre.y())) >> source_log2,
                             static_cast<int>(std::floor(centre.z())) >> source_log2);
      if (gridIndexInRange(index) && observed->contains(packGridIndex(index))) return true;
    }
    const Eigen::Vector3d half_extent = A.cwiseAbs().rowwise().sum() * h;
    const Eigen::Vector3d lo = centre - half_extent;
    const Eigen::Vector3d hi = centre + half_extent;
    BlockIndex b_lo, b_hi;
    int64_t count = 1;
    for (int axis = 0; axis < 3; ++axis) {
      const double margin = 1e-3 + 1e-5 * std::max(std::abs(lo[axis]), std::abs(hi[axis]));
      const double v_lo = std::floor(lo[axis] - margin);
      const double v_hi = std::floor(hi[axis] + margin) + 1.0;
      if (!(v_lo > -kLimit && v_hi < kLimit)) return true;
      b_lo[axis] = static_cast<int>(v_lo) >> source_log2;
      b_hi[axis] = static_cast<int>(v_hi) >> source_log2;
      count *= b_hi[axis] - b_lo[axis] + 1;
    }
    if (count > 64) return true;  // a coarse target over a fine source: just sample
    for (int z = b_lo.z(); z <= b_hi.z(); ++z) {
      for (int y = b_lo.y(); y <= b_hi.y(); ++y) {
        for (int x = b_lo.x(); x <= b_hi.x(); ++x) {
          const BlockIndex index(x, y, z);
          if (gridIndexInRange(index) && observed->contains(packGridIndex(index))) return true;
        }
      }
    }
    return false;
  }
};

// Cell `linear` of a block holding cells_per_side^3 cells, in x-fastest order.
GridIndex cellCorner(int linear, int cells_per_side) {
  return GridIndex(linear % cells_per_side, (linear / cells_per_side) % cells_per_side,
                   linear / (cells_per_side * cells_per_side));
}

// Merges one sample (d_s, w_s, colour_s) into a target voxel, as documented at fuseLayers.
void mergeSample(float d_s, float w_s, const Eigen::Vector3f& color_s,
                 const SubmapFusionConfig& config, TsdfVoxel* voxel) {
  if (voxel->weight <= 0.0f) {
    voxel->distance = d_s;
    voxel->weight = std::min(w_s, config.max_weight);
    if (config.use_color) {
      voxel->color =
          Color{roundChannel(color_s.x()), roundChannel(color_s.y()), roundChannel(color_s.z())};
    }
    return;
  }
  const float w_t = voxel->weight;
  const float w = w_t + w_s;
  voxel->distance = (voxel->distance * w_t + d_s * w_s) / w;
  if (config.use_color) {
    const Eigen::Vector3f color_t(voxel->color.r, voxel->color.g, voxel->color.b);
    const Eigen::Vector3f mixed = (color_t * w_t + color_s * w_s) / w;
    voxel->color = Color{roundChannel(mixed.x()), roundChannel(mixed.y()), roundChannel(mixed.z())};
  }
  voxel->weight = std::min(w, config.max_weight);
}

bool hasObservedVoxel(const Block& block, float min_weight) {
  for (int i = 0; i < block.numVoxels(); ++i) {
    if (block.voxel(i).weight >= min_weight) return true;
  }
  return false;
}

}  // namespace

SubmapFusionStats fuseLayers(const TsdfLayer& source, const Transformationd& T_T_S,
                             const SubmapFusionConfig& config, TsdfLayer* target) {
  const auto start = std::chrono::steady_clock::now();
  const std::string error = config.validate();
  if (!error.empty()) throw std::invalid_argument("SubmapFusionConfig: " + error);
  if (target == nullptr) throw std::invalid_argument("fuseLayers: target is null");
  if (target == &source) throw std::invalid_argument("fuseLayers: source and target are one layer");
  if (!isFinitePose(T_T_S)) throw std::invalid_argument("fuseLayers: T_T_S is not finite");

  SubmapFusionStats stats;
  const double s = source.voxelSize();
  const double t = target->voxelSize();
  const int n_t_log2 = target->voxelsPerSideLog2();
  const int n_s = source.voxelsPerSide();

  // Target global voxel g -> source continuous voxel coordinates q = A g + c.
  const Transformationd T_S_T = T_T_S.inverse();
  const Eigen::Matrix3d A = T_S_T.rotationMatrix() * (t / s);
  const Eigen::Vector3d c =
      (T_S_T.rotationMatrix() * Eigen::Vector3d::Constant(0.5 * t) + T_S_T.translation()) / s -
      Eigen::Vector3d::Constant(0.5);
  const Eigen::Matrix3f A_f = A.cast<float>();

  // Target blocks covering the sampleable region of every observed source block.
  absl::flat_hash_set<uint64_t> target_keys;
  absl::flat_hash_set<uint64_t> observed_source;  // the observed source blocks' keys
  constexpr double kEpsilonVoxels = 1e-4;
  // The global voxel indices of the blocks kGridIndexMin .. kGridIndexMax (exact in double).
  const double min_voxel = std::ldexp(static_cast<double>(kGridIndexMin), n_t_log2);
  const double max_voxel = std::ldexp(static_cast<double>(kGridIndexMax) + 1.0, n_t_log2) - 1.0;
  for (const auto& [key, block] : source.blocks()) {
    if (!hasObservedVoxel(*block, config.min_weight)) continue;
    ++stats.source_blocks;
    observed_source.insert(key);
    const Eigen::Vector3d q_lo = (block->index() * n_s).cast<double>();
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d offset(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
      // From the centre of the voxel before the block's first (rim samples there can reach
      // the block) to the first voxel centre of the +1,+1,+1 neighbour.
      const Eigen::Vector3d p_S = (q_lo + offset * (n_s + 1) - Eigen::Vector3d::Constant(0.5)) * s;
      const Eigen::Vector3d p_T = T_T_S * p_S;
      lo = lo.cwiseMin(p_T);
      hi = hi.cwiseMax(p_T);
    }
    // Target voxels whose centre (g + 1/2) t lies in [lo, hi], within the voxels of the
    // blocks the grid can index: a finite but huge T_T_S (a hostile pose) puts [lo, hi]
    // beyond them, where the cast to int would overflow.
    GlobalVoxelIndex g_lo, g_hi;
    bool outside = false;
    for (int axis = 0; axis < 3; ++axis) {
      const double first = std::max(std::ceil(lo[axis] / t - 0.5 - kEpsilonVoxels), min_voxel);
      const double last = std::min(std::floor(hi[axis] / t - 0.5 + kEpsilonVoxels), max_voxel);
      if (!(first <= last)) {  // empty, off the grid, or NaN
        outside = true;
        break;
      }
      g_lo[axis] = static_cast<int>(first);
      g_hi[axis] = static_cast<int>(last);
    }
    if (outside) continue;
    const BlockIndex b_lo(g_lo.x() >> n_t_log2, g_lo.y() >> n_t_log2, g_lo.z() >> n_t_log2);
    const BlockIndex b_hi(g_hi.x() >> n_t_log2, g_hi.y() >> n_t_log2, g_hi.z() >> n_t_log2);
    for (int z = b_lo.z(); z <= b_hi.z(); ++z) {
      for (int y = b_lo.y(); y <= b_hi.y(); ++y) {
        for (int x = b_lo.x(); x <= b_hi.x(); ++x) {
          const BlockIndex index(x, y, z);
          if (!gridIndexInRange(index)) continue;  // no source data can map there
          target_keys.insert(packGridIndex(index));
        }
      }
    }
  }

  // Allocation is single-threaded; the parallel pass only writes voxels of existing blocks.
  std::vector<Block*> blocks;
  std::vector<uint8_t> newly_allocated;
  blocks.reserve(target_keys.size());
  newly_allocated.reserve(target_keys.size());
  for (const uint64_t key : target_keys) {
    bool fresh = false;
    blocks.push_back(target->allocateBlock(unpackGridIndex(key), &fresh));
    newly_allocated.push_back(fresh ? 1 : 0);
  }
  stats.target_blocks_visited = blocks.size();

  // Per target block: 0 no sample, 1 rim samples only, 2 a sample with every corner observed.
  std::vector<uint8_t> block_used(blocks.size(), 0);
  std::vector<size_t> fused_in_block(blocks.size(), 0);
  std::vector<size_t> fused_per_thread(static_cast<size_t>(config.num_threads), 0);
  std::vector<size_t> sampled_per_thread(static_cast<size_t>(config.num_threads), 0);
  std::atomic<size_t> next_block{0};
  const int n_t = target->voxelsPerSide();
  const int cell = std::min(n_t, kFusionCellVoxels);
  const int cells_per_block = (n_t / cell) * (n_t / cell) * (n_t / cell);
  const CellReach reach{A, c, source.voxelsPerSideLog2(), &observed_source};
  runThreadTeam(config.num_threads, [&](int thread_id) {
    SourceSampler sampler(source, config.min_weight, config.min_sample_coverage);
    size_t fused = 0, sampled = 0;
    for (;;) {
      const size_t b = next_block.fetch_add(1, std::memory_order_relaxed);
      if (b >= blocks.size()) break;
      Block& block = *blocks[b];
      const GlobalVoxelIndex first = block.index() * n_t;
      const Eigen::Vector3f q0 = (A * first.cast<double>() + c).cast<float>();
      size_t fused_here = 0;
      bool interior_here = false;
      for (int linear_cell = 0; linear_cell < cells_per_block; ++linear_cell) {
        const GridIndex corner = cellCorner(linear_cell, n_t / cell) * cell;
        if (!reach.mayReachObservedSource(first + corner, cell)) continue;
        sampled += static_cast<size_t>(cell) * cell * cell;
        for (int z = corner.z(); z < corner.z() + cell; ++z) {
          for (int y = corner.y(); y < corner.y() + cell; ++y) {
            const Eigen::Vector3f q_row =
                q0 + A_f.col(2) * static_cast<float>(z) + A_f.col(1) * static_cast<float>(y);
            for (int x = corner.x(); x < corner.x() + cell; ++x) {
              const Eigen::Vector3f q = q_row + A_f.col(0) * static_cast<float>(x);
              float d_s = 0.0f, w_s = 0.0f;
              Eigen::Vector3f color_s;
              bool complete = false;
              if (!sampler.sample(q, &d_s, &w_s, &color_s, &complete)) continue;
              interior_here = interior_here || complete;
              mergeSample(d_s, w_s, color_s, config, &block.voxel((z * n_t + y) * n_t + x));
              ++fused_here;
            }
          }
        }
      }
      if (fused_here > 0) {
        block_used[b] = interior_here ? 2 : 1;
        fused_in_block[b] = fused_here;
        block.setUpdated(true);
      }
      fused += fused_here;
    }
    fused_per_thread[static_cast<size_t>(thread_id)] = fused;
    sampled_per_thread[static_cast<size_t>(thread_id)] = sampled;
  });
  for (const size_t fused : fused_per_thread) stats.voxels_fused += fused;
  for (const size_t sampled : sampled_per_thread) stats.voxels_sampled += sampled;

  for (size_t b = 0; b < blocks.size(); ++b) {
    if (!newly_allocated[b]) continue;
    // A new block with rim samples only lies beyond the source's observed region: it would
    // grow the map by a one-voxel rim at every fusion, so it is not kept.
    if (block_used[b] == 2) {
      ++stats.target_blocks_allocated;
    } else {
      stats.voxels_fused -= fused_in_block[b];
      target->removeBlock(blocks[b]->index());
    }
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

SubmapFusionStats fuseSubmaps(const Submap& source, Submap* target,
                              const SubmapFusionConfig& config) {
  if (target == nullptr) throw std::invalid_argument("fuseSubmaps: target is null");
  if (target == &source) throw std::invalid_argument("fuseSubmaps: source and target are one");
  if (!source.isFinished() || !target->isFinished()) {
    throw std::invalid_argument("fuseSubmaps: both submaps must be finished (source " +
                                std::to_string(source.id()) + ", target " +
                                std::to_string(target->id()) + ")");
  }
  const Transformationd T_T_S = target->T_G_M().inverse() * source.T_G_M();
  const SubmapFusionStats stats = fuseLayers(source.layer(), T_T_S, config, target->mutableLayer());
  for (const KeyframeId id : source.keyframeIds()) target->addKeyframe(id);
  target->refreshStatistics();
  return stats;
}

TsdfLayer projectCollection(const SubmapCollection& collection, const LayerConfig& layer_config,
                            const SubmapFusionConfig& config, bool include_active,
                            SubmapFusionStats* stats) {
  const std::string error = config.validate();
  if (!error.empty()) throw std::invalid_argument("SubmapFusionConfig: " + error);
  TsdfLayer layer(layer_config);
  SubmapFusionStats total;
  for (const SubmapPose& pose : collection.poseSnapshot()) {
    const std::shared_ptr<Submap> submap = collection.getSubmap(pose.id);
    if (!submap) continue;  // removed since the snapshot
    if (submap->isFinished()) {
      total += fuseLayers(submap->layer(), pose.T_G_M, config, &layer);
    } else if (include_active) {
      const std::unique_lock lock = submap->lockLayer();
      total += fuseLayers(submap->layer(), pose.T_G_M, config, &layer);
    }
  }
  if (stats != nullptr) *stats = total;
  return layer;
}

Mesh meshCollection(const SubmapCollection& collection, const LayerConfig& layer_config,
                    const SubmapFusionConfig& config, const MeshConfig& mesh_config,
                    bool include_active) {
  const std::string error = mesh_config.validate();
  if (!error.empty()) throw std::invalid_argument("MeshConfig: " + error);
  const TsdfLayer layer = projectCollection(collection, layer_config, config, include_active);
  MeshIntegrator mesher(layer, mesh_config);
  mesher.update(/*only_updated_blocks=*/false);
  return mesher.extractMesh(/*connected=*/true);
}

}  // namespace cblox
