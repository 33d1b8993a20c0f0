#include "core/integrator/projective_tsdf_integrator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "core/integrator/thread_team.h"
#include "core/integrator/tsdf_voxel_update.h"

namespace cblox {
namespace {

constexpr int kBlockSetLog2Buckets = 16;
constexpr size_t kBlocksPerClaim = 4;

struct ThreadState {
  IntegrationStats stats;
  std::vector<uint64_t> block_keys;
};

}  // namespace

ProjectiveTsdfIntegrator::ProjectiveTsdfIntegrator(const IntegratorConfig& config,
                                                   TsdfLayer* layer)
    : config_(config), layer_(layer), block_set_(kBlockSetLog2Buckets) {
  if (layer == nullptr) throw std::invalid_argument("ProjectiveTsdfIntegrator: layer is null");
  const std::string error = config.validate(layer->voxelSize());
  if (!error.empty()) throw std::invalid_argument("IntegratorConfig: " + error);
}

IntegrationStats ProjectiveTsdfIntegrator::integrateDepthImage(const Transformation& T_G_C,
                                                              const DepthImage& depth,
                                                              const PinholeCamera& camera,
                                                              const ColorImage* color) {
  const auto start_time = std::chrono::steady_clock::now();
  const PinholeIntrinsics& K = camera.intrinsics();
  if (depth.width != K.width || depth.height != K.height) {
    throw std::invalid_argument("ProjectiveTsdfIntegrator: depth image is " +
                                std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                                " but the camera is " + std::to_string(K.width) + "x" +
                                std::to_string(K.height));
  }
  if (color != nullptr && (color->width != depth.width || color->height != depth.height)) {
    throw std::invalid_argument("ProjectiveTsdfIntegrator: colour image size differs from depth");
  }
  const int width = depth.width;
  const int height = depth.height;
  const int num_threads = config_.num_threads;
  const float truncation = config_.truncation_distance_m;
  const float fx = static_cast<float>(K.fx), fy = static_cast<float>(K.fy);
  const float cx = static_cast<float>(K.cx), cy = static_cast<float>(K.cy);
  const float block_size_inv = layer_->blockSizeInv();
  // A voxel updated from pixel q lies within truncation of q's surface point, up to the
  // half-pixel by which its centre can miss q's ray.
  const float lateral_margin = 0.5f / std::min(fx, fy);

  valid_depth_.width = width;
  valid_depth_.height = height;
  valid_depth_.data.resize(depth.data.size());
  block_set_.clear();
  std::vector<ThreadState> states(static_cast<size_t>(num_threads));

  // Phase A: validate pixels and collect the blocks within truncation of their points.
  std::atomic<int> next_row{0};
  runThreadTeam(num_threads, [&](int id) {
    ThreadState& state = states[static_cast<size_t>(id)];
    for (int v = next_row.fetch_add(1); v < height; v = next_row.fetch_add(1)) {
      BlockIndex previous_lo(1, 1, 1), previous_hi(0, 0, 0);  // an empty range
      const float yn = (static_cast<float>(v) - cy) / fy;
      for (int u = 0; u < width; ++u) {
        const size_t pixel = static_cast<size_t>(v) * static_cast<size_t>(width) + static_cast<size_t>(u);
        const float d = depth.data[pixel];
        valid_depth_.data[pixel] = 0.0f;
        if (!std::isfinite(d) || d <= 0.0f) {
          ++state.stats.points_invalid;
          continue;
        }
        const float xn = (static_cast<float>(u) - cx) / fx;
        const Eigen::Vector3f point_C(xn * d, yn * d, d);
        const float length = point_C.norm();
        if (length < config_.min_ray_length_m || length > config_.max_ray_length_m) {
          ++state.stats.points_out_of_range;
          continue;
        }
        const Eigen::Vector3f point_G = T_G_C * point_C;
        const float radius = truncation + lateral_margin * d;
        const BlockIndex lo = gridIndexFromPoint(Eigen::Vector3f(point_G.array() - radius), block_size_inv);
        const BlockIndex hi = gridIndexFromPoint(Eigen::Vector3f(point_G.array() + radius), block_size_inv);
        if (!gridIndexInRange(lo) || !gridIndexInRange(hi)) {
          ++state.stats.points_invalid;
          continue;
        }
        valid_depth_.data[pixel] = d;
        if (lo == previous_lo && hi == previous_hi) continue;
        previous_lo = lo;
        previous_hi = hi;
        for (int z = lo.z(); z <= hi.z(); ++z) {
          for (int y = lo.y(); y <= hi.y(); ++y) {
            for (int x = lo.x(); x <= hi.x(); ++x) {
              const uint64_t key = packGridIndex(BlockIndex(x, y, z));
              if (block_set_.insert(key)) state.block_keys.push_back(key);
            }
          }
        }
      }
    }
  });

  // Allocation, single-threaded. The approximate set can report a key twice (after an
  // eviction), and every block must be visited exactly once, so deduplicate first.
  std::vector<uint64_t> keys;
  for (const ThreadState& state : states) {
    keys.insert(keys.end(), state.block_keys.begin(), state.block_keys.end());
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<Block*> blocks;
  std::vector<uint8_t> newly_allocated;
  blocks.reserve(keys.size());
  newly_allocated.reserve(keys.size());
  for (const uint64_t key : keys) {
    bool is_new = false;
    blocks.push_back(layer_->allocateBlock(unpackGridIndex(key), &is_new));
    newly_allocated.push_back(is_new ? 1 : 0);
  }

  // Phase B: every voxel of those blocks, projected into the image; one thread per block.
  const TsdfVoxelUpdater updater(config_, layer_->voxelSize());
  const Transformation T_C_G = T_G_C.inverse();
  const Eigen::Matrix3f R_C_G = T_C_G.rotationMatrix();
  const Eigen::Vector3f t_C_G = T_C_G.translation();
  const float voxel_size = layer_->voxelSize();
  const int vps = layer_->voxelsPerSide();
  const Eigen::Vector3f step_x = R_C_G.col(0) * voxel_size;
  const Eigen::Vector3f step_y = R_C_G.col(1) * voxel_size;
  const Eigen::Vector3f step_z = R_C_G.col(2) * voxel_size;
  std::vector<uint8_t> touched(blocks.size(), 0);
  std::atomic<size_t> next_block{0};
  runThreadTeam(num_threads, [&](int id) {
    IntegrationStats& stats = states[static_cast<size_t>(id)].stats;
    for (size_t begin = next_block.fetch_add(kBlocksPerClaim); begin < blocks.size();
         begin = next_block.fetch_add(kBlocksPerClaim)) {
      const size_t end = std::min(begin + kBlocksPerClaim, blocks.size());
      for (size_t b = begin; b < end; ++b) {
        Block& block = *blocks[b];
        TsdfVoxel* voxel = block.voxels();
        const Eigen::Vector3f first_center_C =
            R_C_G * (block.origin() + Eigen::Vector3f::Constant(0.5f * voxel_size)) + t_C_G;
        size_t updates = 0;
        for (int k = 0; k < vps; ++k) {
          for (int j = 0; j < vps; ++j) {
            Eigen::Vector3f p_C = first_center_C + static_cast<float>(k) * step_z +
                                  static_cast<float>(j) * step_y;
            for (int i = 0; i < vps; ++i, ++voxel, p_C += step_x) {
              if (p_C.z() <= 1e-6f) continue;
              const float inv_z = 1.0f / p_C.z();
              const int u = static_cast<int>(std::floor(fx * p_C.x() * inv_z + cx + 0.5f));
              const int v = static_cast<int>(std::floor(fy * p_C.y() * inv_z + cy + 0.5f));
              if (u < 0 || u >= width || v < 0 || v >= height) continue;
              const size_t pixel = static_cast<size_t>(v) * static_cast<size_t>(width) + static_cast<size_t>(u);
              const float d = valid_depth_.data[pixel];
              if (d <= 0.0f) continue;
              const float sdf = (d - p_C.z()) * p_C.norm() * inv_z;
              const Color c = color != nullptr ? color->data[pixel] : Color{};
              if (updater.update(sdf, updater.measurementWeight(d), c, voxel)) ++updates;
            }
          }
        }
        if (updates > 0) {
          touched[b] = 1;
          block.setUpdated(true);
          stats.voxel_updates += updates;
        }
      }
    }
  });

  IntegrationStats stats;
  for (const ThreadState& state : states) stats += state.stats;
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (!newly_allocated[b]) continue;
    if (touched[b]) {
      ++stats.blocks_allocated;
    } else {
      layer_->removeBlock(blocks[b]->index());
    }
  }
  stats.points_in = depth.data.size();
  stats.rays_cast = 0;
  stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return stats;
}

}  // namespace cblox
