#include "core/integrator/projective_tsdf_integrator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/common/thread_team.h"
#include "core/integrator/deadline.h"
#include "core/integrator/depth_groups.h"
#include "core/integrator/even_coverage_order.h"

#include "core/integrator/projective_block_screen.h"
#include "core/integrator/projective_voxel_rows.h"
#include "core/integrator/tsdf_voxel_update.h"

namespace cblox {
namespace {

constexpr int kBlockSetLog2Buckets = 16;
// The largest block cube of the search (2 MiB of bits): 5 m rays and 16 cm blocks take 57 KiB.
constexpr size_t kBlockCubeMaxBits = size_t{1} << 24;
constexpr size_t kBlocksPerClaim = 4;
constexpr int kSearchCellPixels = 8;  // block search cell (pixels per side)
// Squares of up to 8 cells in the screen's table: a block's part 0.5 m away spans about
// 20 cells on 640x480 frames, 6 lookups.
constexpr int kCellTableLevels = 4;

struct ThreadState {
  IntegrationStats stats;
  std::vector<uint64_t> block_keys;
};

// Writes one image row's depths next to their ray factors: the depth where it is finite,
// > 0 and its ray length (depth * ray factor) is within [min_length, max_length], else 0;
// counts the rejected pixels.
void validateRow(const float* depth, ProjectivePixelSample* samples, int width, float min_length,
                 float max_length, IntegrationStats* stats) {
  size_t invalid = 0, out_of_range = 0;
  int u = 0;
#if defined(__SSE2__)
  const __m128 zero = _mm_setzero_ps();
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 lo = _mm_set1_ps(min_length), hi = _mm_set1_ps(max_length);
  // Per-lane counts: a true mask is -1, so subtracting it counts one (a lane sees at most
  // width / 4 pixels).
  __m128i ok_count = _mm_setzero_si128(), out_count = _mm_setzero_si128();
  for (; u + 4 <= width; u += 4) {
    float* p = reinterpret_cast<float*>(samples + u);
    const __m128 d = _mm_loadu_ps(depth + u);
    const __m128 s01 = _mm_loadu_ps(p), s23 = _mm_loadu_ps(p + 4);
    const __m128 ray_factor = _mm_shuffle_ps(s01, s23, _MM_SHUFFLE(3, 1, 3, 1));
    // Finite and > 0 (NaN fails both comparisons).
    const __m128 ok = _mm_and_ps(_mm_cmpgt_ps(d, zero), _mm_cmplt_ps(d, inf));
    const __m128 length = _mm_mul_ps(d, ray_factor);
    const __m128 in_range = _mm_and_ps(_mm_cmpge_ps(length, lo), _mm_cmple_ps(length, hi));
    const __m128 valid = _mm_and_ps(ok, in_range);
    ok_count = _mm_sub_epi32(ok_count, _mm_castps_si128(ok));
    out_count = _mm_sub_epi32(out_count, _mm_castps_si128(_mm_andnot_ps(in_range, ok)));
    const __m128 kept = _mm_and_ps(valid, d);
    _mm_storeu_ps(p, _mm_unpacklo_ps(kept, ray_factor));
    _mm_storeu_ps(p + 4, _mm_unpackhi_ps(kept, ray_factor));
  }
  alignas(16) int32_t ok_lanes[4], out_lanes[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(ok_lanes), ok_count);
  _mm_store_si128(reinterpret_cast<__m128i*>(out_lanes), out_count);
  for (int k = 0; k < 4; ++k) {
    invalid += static_cast<size_t>(u / 4 - ok_lanes[k]);
    out_of_range += static_cast<size_t>(out_lanes[k]);
  }
#endif
  for (; u < width; ++u) {
    const float d = depth[u];
    float valid = 0.0f;
    if (!std::isfinite(d) || d <= 0.0f) {
      ++invalid;
    } else if (const float length = d * samples[u].ray_factor;
               length < min_length || length > max_length) {
      ++out_of_range;
    } else {
      valid = d;
    }
    samples[u].depth = valid;
  }
  stats->points_invalid += invalid;
  stats->points_out_of_range += out_of_range;
}

// The valid depths (> 0) of the pixels [u0, u1) x [v0, v1): how many, the nearest and
// the farthest.
struct DepthRange {
  int count = 0;
  float d_min = std::numeric_limits<float>::infinity();
  float d_max = 0.0f;
};
DepthRange cellDepthRange(const ProjectivePixelSample* samples, int width, int u0, int v0, int u1,
                          int v1) {
  DepthRange range;
#if defined(__SSE2__)
  if (u1 - u0 == 8) {  // a full cell row: two vectors of four depths (the rejected are 0)
    const __m128 zero = _mm_setzero_ps();
    const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
    __m128 lo = inf, hi = zero;
    int count = 0;
    for (int v = v0; v < v1; ++v) {
      const float* p =
          reinterpret_cast<const float*>(samples + static_cast<size_t>(v) * width + u0);
      for (int half = 0; half < 2; ++half, p += 8) {
        const __m128 d =
            _mm_shuffle_ps(_mm_loadu_ps(p), _mm_loadu_ps(p + 4), _MM_SHUFFLE(2, 0, 2, 0));
        const __m128 valid = _mm_cmpgt_ps(d, zero);
        lo = _mm_min_ps(lo, _mm_or_ps(_mm_and_ps(valid, d), _mm_andnot_ps(valid, inf)));
        hi = _mm_max_ps(hi, d);
        count += __builtin_popcount(static_cast<unsigned>(_mm_movemask_ps(valid)));
      }
    }
    lo = _mm_min_ps(lo, _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(1, 0, 3, 2)));
    hi = _mm_max_ps(hi, _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(1, 0, 3, 2)));
    lo = _mm_min_ss(lo, _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(2, 3, 0, 1)));
    hi = _mm_max_ss(hi, _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(2, 3, 0, 1)));
    range.count = count;
    range.d_min = _mm_cvtss_f32(lo);
    range.d_max = _mm_cvtss_f32(hi);
    return range;
  }
#endif
  for (int v = v0; v < v1; ++v) {
    const ProjectivePixelSample* row = samples + static_cast<size_t>(v) * width;
    for (int u = u0; u < u1; ++u) {
      const float d = row[u].depth;
      if (d > 0.0f) {
        ++range.count;
        range.d_min = std::min(range.d_min, d);
        range.d_max = std::max(range.d_max, d);
      }
    }
  }
  return range;
}

bool sameIntrinsics(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && a.width == b.width &&
         a.height == b.height;
}

}  // namespace

ProjectiveTsdfIntegrator::ProjectiveTsdfIntegrator(const IntegratorConfig& config, TsdfLayer* layer)
    : config_(config),
      layer_(layer),
      block_cube_(kBlockCubeMaxBits),
      block_set_(kBlockSetLog2Buckets) {
  if (layer == nullptr) throw std::invalid_argument("ProjectiveTsdfIntegrator: layer is null");
  const std::string error = config.validate(layer->voxelSize());
  if (!error.empty()) throw std::invalid_argument("IntegratorConfig: " + error);
}

// A search cell's centre ray in the layer frame, and how far the cell's rays can leave it.
struct ProjectiveTsdfIntegrator::CellRay {
  Eigen::Vector3f origin_G;     // the sensor
  Eigen::Vector3f direction_G;  // R_G_C (x_n, y_n, 1) of the cell's centre: depth d is at
                                // origin_G + d * direction_G
  float truncation_radius;      // the truncation along that ray, truncation * ||(x_n, y_n, 1)||
  float lateral_per_depth;      // the cell's half diagonal plus half a pixel, per metre of depth
};

void ProjectiveTsdfIntegrator::collectBlocks(const Eigen::Matrix3f& R_G_C,
                                             const Eigen::Vector3f& t_G_C, int u0, int v0,
                                             std::vector<uint64_t>* keys) {
  const int width = width_, height = height_;
  const int u1 = std::min(u0 + kSearchCellPixels, width);
  const int v1 = std::min(v0 + kSearchCellPixels, height);
  const DepthRange range = cellDepthRange(samples_.data(), width, u0, v0, u1, v1);
  cell_depth_table_.grid()[static_cast<size_t>(v0 / kSearchCellPixels) * cell_depth_table_.width() +
                           u0 / kSearchCellPixels] = range.count > 0 ? range.d_max : 0.0f;
  if (range.count == 0) return;  // no valid pixel
  const float truncation = config_.truncation_distance_m;
  // The cell's rays leave its centre ray by at most half its diagonal (plus the half pixel
  // by which a voxel centre can miss its pixel's ray).
  const PinholeIntrinsics& K = factor_camera_;
  const float f_min = static_cast<float>(std::min(K.fx, K.fy));
  const float uc = 0.5f * static_cast<float>(u0 + u1 - 1),
              vc = 0.5f * static_cast<float>(v0 + v1 - 1);
  const Eigen::Vector3f ray_C((uc - static_cast<float>(K.cx)) / static_cast<float>(K.fx),
                              (vc - static_cast<float>(K.cy)) / static_cast<float>(K.fy), 1.0f);
  const CellRay ray{t_G_C, R_G_C * ray_C, truncation * ray_C.norm(),
                    (0.7072f * static_cast<float>(std::max(u1 - u0, v1 - v0)) + 0.5f) / f_min};
  // The free space in front of the cell's nearest depth, from the sensor's near limit.
  const float carve_to = std::min(range.d_min - truncation, config_.projective_carving_depth_m);
  if (carve_to > config_.min_ray_length_m) {
    addSegmentBlocks(ray, config_.min_ray_length_m, carve_to, keys);
  }
  if (range.d_max - range.d_min <= truncation) {
    addSegmentBlocks(ray, range.d_min, range.d_max, keys);
    return;
  }
  // Groups of depths separated by more than the truncation: one segment each.
  float depths[kSearchCellPixels * kSearchCellPixels] = {};
  int n = 0;
  for (int v = v0; v < v1; ++v) {
    const ProjectivePixelSample* row =
        &samples_[static_cast<size_t>(v) * static_cast<size_t>(width)];
    for (int u = u0; u < u1; ++u) {
      if (row[u].depth > 0.0f) depths[n++] = row[u].depth;
    }
  }
  forEachDepthGroup(depths, n, range.d_min, range.d_max, truncation,
                    [&](float first, float last) { addSegmentBlocks(ray, first, last, keys); });
}

void ProjectiveTsdfIntegrator::addSegmentBlocks(const CellRay& ray, float d_min, float d_max,
                                                std::vector<uint64_t>* keys) {
  const float radius = ray.truncation_radius + ray.lateral_per_depth * d_max;
  const Eigen::Vector3f a = ray.origin_G + ray.direction_G * d_min;
  const Eigen::Vector3f b = ray.origin_G + ray.direction_G * d_max;
  // Finite and inside the packable grid: the frame's pose was checked, and rejected pixels
  // have no depth.
  const float block_size_inv = layer_->blockSizeInv();
  const BlockIndex lo =
      gridIndexFromPointUnchecked(Eigen::Vector3f(a.cwiseMin(b).array() - radius), block_size_inv);
  const BlockIndex hi =
      gridIndexFromPointUnchecked(Eigen::Vector3f(a.cwiseMax(b).array() + radius), block_size_inv);
  // Keep the blocks of that box that can hold a voxel within `radius` of the segment a-b:
  // block centre within radius + the largest distance from it to one of its voxel centres
  // (half the diagonal of the cube the centres span, block size less one voxel).
  const float block_size = layer_->blockSize();
  const float reach = radius + 0.8661f * (block_size - layer_->voxelSize());
  const Eigen::Vector3f ab = b - a;
  const float ab_squared = std::max(ab.squaredNorm(), 1e-12f);
  const auto withinReach = [&](int x, int y, int z) {
    const Eigen::Vector3f centre =
        (Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)) +
         Eigen::Vector3f::Constant(0.5f)) *
        block_size;
    const float t = std::clamp((centre - a).dot(ab) / ab_squared, 0.0f, 1.0f);
    return (a + t * ab - centre).squaredNorm() <= reach * reach;
  };
  // Neighbouring cells find mostly the same blocks (93 % of the blocks of a cell's box on the
  // 7-Scenes frames): a box row along x is consecutive bits of the cube, read up to 64 at
  // once, and only the blocks not found yet take the distance test.
  if (block_cube_.covers(lo, hi)) {
    const size_t side = block_cube_.side();
    const size_t first = block_cube_.bitOf(lo.x(), lo.y(), lo.z());
    for (int x0 = lo.x(); x0 <= hi.x(); x0 += 64) {  // once, unless the box is wider
      const int n = std::min(64, hi.x() - x0 + 1);
      const uint64_t all = n == 64 ? ~uint64_t{0} : (uint64_t{1} << n) - 1;
      size_t plane = first + static_cast<size_t>(x0 - lo.x());
      for (int z = lo.z(); z <= hi.z(); ++z, plane += side * side) {
        size_t row = plane;
        for (int y = lo.y(); y <= hi.y(); ++y, row += side) {
          for (uint64_t missing = ~block_cube_.run(row, n) & all; missing != 0;
               missing &= missing - 1) {
            const int i = __builtin_ctzll(missing);
            if (!withinReach(x0 + i, y, z)) continue;
            if (block_cube_.insert(row + static_cast<size_t>(i))) {
              keys->push_back(packGridIndex(BlockIndex(x0 + i, y, z)));
            }
          }
        }
      }
    }
    return;
  }
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const uint64_t key = packGridIndex(BlockIndex(x, y, z));
        if (block_set_.contains(key) || !withinReach(x, y, z)) continue;
        if (block_set_.insert(key)) keys->push_back(key);
      }
    }
  }
}

IntegrationStats ProjectiveTsdfIntegrator::integrateDepthImage(const Transformation& T_G_C,
                                                               const DepthImage& depth,
                                                               const PinholeCamera& camera,
                                                               const ColorImage* color) {
  const auto start_time = std::chrono::steady_clock::now();
  const Deadline deadline(config_.max_integration_time_s);
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
  // The ray factors depend only on the camera: computed once, then each frame writes
  // only the depths next to them.
  if (samples_.empty() || !sameIntrinsics(factor_camera_, K)) {
    factor_camera_ = K;
    samples_.resize(static_cast<size_t>(width) * static_cast<size_t>(height));
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const double xn = (u - K.cx) / K.fx, yn = (v - K.cy) / K.fy;
        samples_[static_cast<size_t>(v) * width + u] = {
            0.0f, static_cast<float>(std::sqrt(1.0 + xn * xn + yn * yn))};
      }
    }
  }
  // Every point must stay inside the packable grid (absurd poses are rejected whole).
  const float coordinate_limit =
      (kGridIndexMax - 2) * layer_->voxelSize() - 2.0f * config_.max_ray_length_m;
  const bool pose_in_range = T_G_C.translation().cwiseAbs().maxCoeff() < coordinate_limit;

  width_ = width;
  height_ = height;
  block_set_.clear();
  // The cube around the sensor holding every segment box: the boxes reach a ray length
  // (<= max_ray_length, times the few per cent by which a cell's centre ray can be longer
  // than its pixels') plus the truncation and the cell's width; any box outside it, or a
  // cube too large, falls back to block_set_.
  const float cube_half_side =
      std::ceil((1.1f * config_.max_ray_length_m + 2.0f * config_.truncation_distance_m) *
                layer_->blockSizeInv()) +
      2.0f;
  if (pose_in_range && cube_half_side < 1024.0f) {  // larger cubes exceed kBlockCubeMaxBits
    block_cube_.reset(gridIndexFromPointUnchecked(T_G_C.translation(), layer_->blockSizeInv()),
                      static_cast<int>(cube_half_side));
  } else {
    block_cube_.reset(BlockIndex::Zero(), -1);  // unusable: every box goes to block_set_
  }
  std::vector<ThreadState> states(static_cast<size_t>(num_threads));

  // Phase A: validate pixels (rows), then collect the blocks of each search cell.
  const float min_length = config_.min_ray_length_m, max_length = config_.max_ray_length_m;
  std::atomic<int> next_row{0};
  runThreadTeam(num_threads, [&](int id) {
    IntegrationStats& stats = states[static_cast<size_t>(id)].stats;
    for (int v = next_row.fetch_add(1); v < height; v = next_row.fetch_add(1)) {
      const size_t row = static_cast<size_t>(v) * static_cast<size_t>(width);
      if (pose_in_range) {
        validateRow(&depth.data[row], &samples_[row], width, min_length, max_length, &stats);
      } else {  // every pixel is rejected
        for (int u = 0; u < width; ++u) samples_[row + u].depth = 0.0f;
        stats.points_invalid += static_cast<size_t>(width);
      }
    }
  });
  const Eigen::Matrix3f R_G_C = T_G_C.rotationMatrix();  // one matrix per frame, not per cell
  const Eigen::Vector3f t_G_C = T_G_C.translation();
  const int cells_x = (width + kSearchCellPixels - 1) / kSearchCellPixels;
  const int cells_y = (height + kSearchCellPixels - 1) / kSearchCellPixels;
  cell_depth_table_.resetGrid(cells_x, cells_y, kCellTableLevels);
  std::atomic<int> next_cell{0};
  runThreadTeam(num_threads, [&](int id) {
    ThreadState& state = states[static_cast<size_t>(id)];
    for (int c = next_cell.fetch_add(1); c < cells_x * cells_y; c = next_cell.fetch_add(1)) {
      collectBlocks(R_G_C, t_G_C, (c % cells_x) * kSearchCellPixels,
                    (c / cells_x) * kSearchCellPixels, &state.block_keys);
    }
  });

  // Allocation, single-threaded (after the screen below, in parallel). The approximate set can
  // report a key twice (after an eviction), and every block must be visited exactly once, so
  // deduplicate first.
  std::vector<uint64_t> keys;
  for (const ThreadState& state : states) {
    keys.insert(keys.end(), state.block_keys.begin(), state.block_keys.end());
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const Transformation T_C_G = T_G_C.inverse();
  const Eigen::Matrix3f R_C_G = T_C_G.rotationMatrix();
  const Eigen::Vector3f t_C_G = T_C_G.translation();
  const float voxel_size = layer_->voxelSize();
  const float fx = static_cast<float>(K.fx), fy = static_cast<float>(K.fy);
  const float cx = static_cast<float>(K.cx), cy = static_cast<float>(K.cy);
  cell_depth_table_.buildLevels();
  // Blocks no voxel of which can be updated are neither allocated nor visited (on the
  // 7-Scenes frames half of the blocks that were allocated for a frame and freed unused).
  const ProjectiveBlockScreen screen({R_C_G, t_C_G, fx, fy, cx + 0.5f, cy + 0.5f, width, height,
                                      voxel_size, layer_->voxelsPerSide(),
                                      config_.truncation_distance_m, &cell_depth_table_,
                                      kSearchCellPixels});
  std::vector<Block*> blocks;
  std::vector<uint8_t> newly_allocated;
  blocks.reserve(keys.size());
  newly_allocated.reserve(keys.size());
  std::vector<uint8_t> quadrants(keys.size());  // ProjectiveBlockScreen::rowQuadrants
  std::atomic<size_t> next_key{0};
  constexpr size_t kKeysPerClaim = 64;
  runThreadTeam(num_threads, [&](int) {
    for (size_t k0 = next_key.fetch_add(kKeysPerClaim); k0 < keys.size();
         k0 = next_key.fetch_add(kKeysPerClaim)) {
      for (size_t k = k0; k < std::min(k0 + kKeysPerClaim, keys.size()); ++k) {
        quadrants[k] = static_cast<uint8_t>(
            screen.rowQuadrants(unpackGridIndex(keys[k]).cast<float>() * layer_->blockSize()));
      }
    }
  });
  std::vector<uint8_t> block_quadrants;
  block_quadrants.reserve(keys.size());
  for (size_t k = 0; k < keys.size(); ++k) {
    if (quadrants[k] == 0) continue;
    bool is_new = false;
    blocks.push_back(layer_->allocateBlock(unpackGridIndex(keys[k]), &is_new));
    newly_allocated.push_back(is_new ? 1 : 0);
    block_quadrants.push_back(quadrants[k]);
  }

  // Phase B: every voxel of those blocks, projected into the image; one thread per block.
  const TsdfVoxelUpdater updater(config_, layer_->voxelSize());
  const int vps = layer_->voxelsPerSide();
  const Eigen::Vector3f step_x = R_C_G.col(0) * voxel_size;
  const Eigen::Vector3f step_y = R_C_G.col(1) * voxel_size;
  const Eigen::Vector3f step_z = R_C_G.col(2) * voxel_size;
  // Rows of voxels run along x (consecutive in memory); row r = k * vps + j starts at the
  // block's first voxel centre plus k * step_z + j * step_y, the same for every block.
  std::vector<Eigen::Vector3f> row_offsets(static_cast<size_t>(vps) * static_cast<size_t>(vps));
  for (int k = 0, r = 0; k < vps; ++k) {
    for (int j = 0; j < vps; ++j, ++r) {
      row_offsets[static_cast<size_t>(r)] =
          static_cast<float>(k) * step_z + static_cast<float>(j) * step_y;
    }
  }
  // Visit blocks in image order (16-pixel tiles of their centre's projection), so that
  // consecutive blocks read neighbouring depth and colour pixels.
  {
    std::vector<std::pair<uint32_t, size_t>> order(blocks.size());
    const Eigen::Vector3f half_block = Eigen::Vector3f::Constant(0.5f * layer_->blockSize());
    for (size_t b = 0; b < blocks.size(); ++b) {
      const Eigen::Vector3f c = R_C_G * (blocks[b]->origin() + half_block) + t_C_G;
      const float z = std::max(c.z(), 1e-3f);
      const int u = std::clamp(static_cast<int>(fx * c.x() / z + cx + 0.5f), 0, width - 1) >> 4;
      const int v = std::clamp(static_cast<int>(fy * c.y() / z + cy + 0.5f), 0, height - 1) >> 4;
      order[b] = {static_cast<uint32_t>(v * ((width >> 4) + 1) + u), b};
    }
    std::sort(order.begin(), order.end());
    std::vector<Block*> sorted_blocks(blocks.size());
    std::vector<uint8_t> sorted_new(blocks.size()), sorted_quadrants(blocks.size());
    for (size_t b = 0; b < blocks.size(); ++b) {
      sorted_blocks[b] = blocks[order[b].second];
      sorted_new[b] = newly_allocated[order[b].second];
      sorted_quadrants[b] = block_quadrants[order[b].second];
    }
    blocks.swap(sorted_blocks);
    newly_allocated.swap(sorted_new);
    block_quadrants.swap(sorted_quadrants);
  }
  std::vector<uint8_t> touched(blocks.size(), 0);
  // Claims of kBlocksPerClaim neighbouring blocks; under a time budget they are taken in
  // bit-reversed order, so whatever part of the frame fits in the budget covers it evenly.
  const size_t num_claims = (blocks.size() + kBlocksPerClaim - 1) / kBlocksPerClaim;
  const std::vector<uint32_t> claim_order =
      config_.max_integration_time_s > 0.0 ? evenCoverageOrder(static_cast<uint32_t>(num_claims))
                                           : std::vector<uint32_t>();
  std::atomic<size_t> next_claim{0};
  const Color* const colors = color != nullptr && config_.color_blending != ColorBlending::kNone
                                  ? color->data.data()
                                  : nullptr;
  const ProjectiveVoxelRows rows({fx, fy, cx, cy, width, height, samples_.data(), colors}, updater,
                                 config_.vectorized);
  const unsigned all_quadrants = screen.nonemptyQuadrants();
  runThreadTeam(num_threads, [&](int id) {
    IntegrationStats& stats = states[static_cast<size_t>(id)].stats;
    std::vector<Eigen::Vector3f> row_origins(static_cast<size_t>(vps) * static_cast<size_t>(vps));
    for (size_t taken = next_claim.fetch_add(1); taken < num_claims;
         taken = next_claim.fetch_add(1)) {
      const size_t claim = claim_order.empty() ? taken : claim_order[taken];
      const size_t begin = claim * kBlocksPerClaim;
      const size_t end = std::min(begin + kBlocksPerClaim, blocks.size());
      if (deadline.expired()) {
        stats.blocks_not_reached += end - begin;
        stats.budget_exhausted = true;
        continue;
      }
      for (size_t b = begin; b < end; ++b) {
        Block& block = *blocks[b];
        TsdfVoxel* const voxel = block.voxels();
        const Eigen::Vector3f first_center_C =
            R_C_G * (block.origin() + Eigen::Vector3f::Constant(0.5f * voxel_size)) + t_C_G;
        for (size_t r = 0; r < row_origins.size(); ++r) {
          row_origins[r] = first_center_C + row_offsets[r];
        }
        // The rows of the quadrants the screen kept: all in one call, else per z half the
        // whole half (both y halves kept: consecutive rows) or each row range of one y half.
        const unsigned kept = block_quadrants[b];
        size_t updates = 0;
        if (kept == all_quadrants) {
          updates = rows.update(row_origins.data(), vps * vps, step_x, vps, voxel);
        } else {
          for (int z_half = 0; z_half < 2; ++z_half) {
            const unsigned y_halves = (kept >> (2 * z_half)) & 3u;
            if (y_halves == 0) continue;
            const int k0 = ProjectiveBlockScreen::halfBegin(vps, z_half);
            const int k1 = ProjectiveBlockScreen::halfEnd(vps, z_half);
            if (y_halves == 3u) {
              const int r0 = k0 * vps;
              updates += rows.update(&row_origins[static_cast<size_t>(r0)], (k1 - k0) * vps, step_x,
                                     vps, voxel + static_cast<size_t>(r0) * vps);
              continue;
            }
            const int y_half = y_halves == 1u ? 0 : 1;
            const int j0 = ProjectiveBlockScreen::halfBegin(vps, y_half);
            const int j1 = ProjectiveBlockScreen::halfEnd(vps, y_half);
            for (int k = k0; k < k1; ++k) {
              const int r0 = k * vps + j0;
              updates += rows.update(&row_origins[static_cast<size_t>(r0)], j1 - j0, step_x, vps,
                                     voxel + static_cast<size_t>(r0) * vps);
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
  stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return stats;
}

}  // namespace cblox
