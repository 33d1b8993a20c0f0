#include "core/mapping/mesh_mirror.h"

#include <cmath>

namespace cblox {

MeshMirror::Result MeshMirror::apply(const MeshUpdate& update) {
  Result result;
  if (!std::isfinite(update.block_size) || update.block_size <= 0.0f) {
    result.error = "block_size " + std::to_string(update.block_size) + " is not a positive size";
    return result;
  }
  for (const MeshBlockUpdate& b : update.blocks) {
    if (!gridIndexInRange(b.index)) {
      result.error = "subvolume " + std::to_string(b.submap) + ": block index out of range";
      return result;
    }
    if (std::string e = b.mesh.validate(); !e.empty()) {
      result.error = "subvolume " + std::to_string(b.submap) + " block (" +
                     std::to_string(b.index.x()) + ", " + std::to_string(b.index.y()) + ", " +
                     std::to_string(b.index.z()) + "): " + e;
      return result;
    }
  }
  result.applied = true;
  if (!seen_any_ || update.map_epoch != epoch_) {
    blocks_.clear();
    synced_ = false;
    epoch_ = update.map_epoch;
  } else if (update.sequence != last_sequence_ + 1) {
    synced_ = false;
  }
  if (update.refresh_start) {
    blocks_.clear();
    synced_ = true;
  }
  result.gap = !synced_;
  seen_any_ = true;
  last_sequence_ = update.sequence;
  pending_ = update.blocks_pending;
  block_size_ = update.block_size;
  for (const SubmapId id : update.removed_submaps) blocks_.erase(id);
  for (const MeshBlockUpdate& b : update.blocks) {
    const uint64_t key = packGridIndex(b.index);
    if (b.mesh.empty()) {
      const auto it = blocks_.find(b.submap);
      if (it == blocks_.end()) continue;
      it->second.erase(key);
      if (it->second.empty()) blocks_.erase(it);
    } else {
      blocks_[b.submap][key] = b.mesh;
    }
  }
  return result;
}

void MeshMirror::applySubvolumes(const SubvolumeList& list) { subvolumes_ = list; }

size_t MeshMirror::numBlocks() const {
  size_t n = 0;
  for (const auto& [id, blocks] : blocks_) n += blocks.size();
  return n;
}

Mesh MeshMirror::meshInG() const {
  Mesh out;
  if (subvolumes_.map_epoch != epoch_) return out;
  for (const SubvolumeView& view : subvolumes_.subvolumes) {
    const auto it = blocks_.find(view.id);
    if (it == blocks_.end()) continue;
    const Transformation T_G_S = view.T_G_S.cast<float>();
    for (const auto& [key, q] : it->second) {
      const Eigen::Vector3d center =
          (unpackGridIndex(key).cast<double>() + Eigen::Vector3d::Constant(0.5)) *
          static_cast<double>(block_size_);
      out.append(transformMesh(T_G_S, dequantizeBlockMesh(q, center, block_size_)));
    }
  }
  return out;
}

}  // namespace cblox
