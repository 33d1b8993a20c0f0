#include "core/mapping/memory_cap.h"

#include <cmath>
#include <vector>

#include "core/tsdf/block_index.h"

namespace cblox {

std::string MemoryCapConfig::validate() const {
  if (!(near_only_fraction > 0.0 && near_only_fraction <= 1.0)) {
    return "near_only_fraction must be in (0, 1], got " + std::to_string(near_only_fraction);
  }
  if (!(near_distance_m > 0.0f) || !std::isfinite(near_distance_m)) {
    return "near_distance_m must be finite and > 0, got " + std::to_string(near_distance_m);
  }
  if (cap_mb > (size_t{1} << 40)) return "cap_mb is absurdly large: " + std::to_string(cap_mb);
  return {};
}

const char* memoryCapStateName(MemoryCapState state) {
  switch (state) {
    case MemoryCapState::kOff:
      return "off";
    case MemoryCapState::kBelow:
      return "below";
    case MemoryCapState::kNearOnly:
      return "near_only";
    case MemoryCapState::kFull:
      return "full";
  }
  return "?";
}

MemoryCapState memoryCapState(const MemoryCapConfig& config, size_t map_bytes) {
  if (!config.enabled()) return MemoryCapState::kOff;
  const double cap = static_cast<double>(config.capBytes());
  const double bytes = static_cast<double>(map_bytes);
  if (bytes >= cap) return MemoryCapState::kFull;
  if (bytes >= config.near_only_fraction * cap) return MemoryCapState::kNearOnly;
  return MemoryCapState::kBelow;
}

size_t cutDepthBeyond(DepthImage* depth, float max_depth_m) {
  size_t cut = 0;
  for (float& d : depth->data) {
    if (d > max_depth_m) {
      d = 0.0f;
      ++cut;
    }
  }
  return cut;
}

size_t cutDepthOutsideBlocks(DepthImage* depth, const PinholeIntrinsics& K,
                             const Transformation& T_M_D, const TsdfLayer& layer) {
  size_t cut = 0;
  const float fx_inv = static_cast<float>(1.0 / K.fx), fy_inv = static_cast<float>(1.0 / K.fy);
  const float cx = static_cast<float>(K.cx), cy = static_cast<float>(K.cy);
  for (int v = 0; v < depth->height; ++v) {
    for (int u = 0; u < depth->width; ++u) {
      float& d = (*depth)(u, v);
      if (!(d > 0.0f)) continue;
      const Eigen::Vector3f p_D((static_cast<float>(u) - cx) * fx_inv * d,
                                (static_cast<float>(v) - cy) * fy_inv * d, d);
      if (layer.getBlock(layer.blockIndexFromPoint(T_M_D * p_D)) == nullptr) {
        d = 0.0f;
        ++cut;
      }
    }
  }
  return cut;
}

void NewBlockRefusal::remember(const TsdfLayer& layer) {
  before_.clear();
  before_.reserve(layer.numBlocks());
  for (const auto& entry : layer.blocks()) before_.insert(entry.first);
}

size_t NewBlockRefusal::removeNewBlocks(TsdfLayer* layer) {
  if (layer->numBlocks() == before_.size()) return 0;  // nothing allocated (none removed)
  std::vector<uint64_t> added;
  for (const auto& entry : layer->blocks()) {
    if (!before_.contains(entry.first)) added.push_back(entry.first);
  }
  for (const uint64_t key : added) layer->removeBlock(unpackGridIndex(key));
  return added.size();
}

}  // namespace cblox
