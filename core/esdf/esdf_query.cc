#include "core/esdf/esdf_query.h"

#include <algorithm>
#include <cmath>

namespace cblox {

namespace {

/// The voxel at `index` and its block. `hint` (may be null) is a block near it: when the
/// voxel's block is `hint` or adjacent to it, it is found through hint's neighbour pointers
/// (null there means absent), otherwise by a hash lookup.
struct VoxelRef {
  const EsdfBlock* block = nullptr;
  const EsdfVoxel* voxel = nullptr;
};

VoxelRef locate(const EsdfLayer& layer, const EsdfBlock* hint, const GlobalVoxelIndex& index) {
  BlockIndex block_index;
  GridIndex local;
  splitGlobalVoxelIndex(index, layer.voxelsPerSideLog2(), &block_index, &local);
  const EsdfBlock* block = nullptr;
  if (hint != nullptr) {
    const BlockIndex d = block_index - hint->index;
    block =
        (d.array().abs() <= 1).all()
            ? hint->neighbours[static_cast<size_t>(EsdfBlock::neighbourSlot(d.x(), d.y(), d.z()))]
            : layer.getBlock(block_index);
  } else {
    block = layer.getBlock(block_index);
  }
  if (block == nullptr) return {};
  return {block, &block->voxel(layer.linearIndex(local))};
}

/// voxelDistance() of the voxel `ref`.
void distanceOf(const EsdfLayer& layer, const VoxelRef& ref, VoxelState* state, float* distance) {
  const EsdfVoxel* v = ref.voxel;
  *state = v->state;
  // A site holds its TSDF distance, any other voxel with a site what the wave carried to it.
  *distance = v->hasSite() ? std::min(v->own_distance, layer.maxDistance()) : layer.maxDistance();
}

/// queryNearest() of the voxel `index`, found from `hint` (may be null). An unknown voxel's
/// distance is not answered; the obstacle distance it carries is its bound.
DistanceSample nearestSample(const EsdfLayer& layer, const EsdfBlock* hint,
                             const GlobalVoxelIndex& index) {
  DistanceSample sample;
  const VoxelRef ref = locate(layer, hint, index);
  if (ref.voxel == nullptr) return sample;
  float distance = 0.0f;
  distanceOf(layer, ref, &sample.state, &distance);
  if (sample.state == VoxelState::kUnknown) {
    if (ref.voxel->hasSite()) sample.bound = distance;
  } else {
    sample.distance = distance;
  }
  return sample;
}

/// Trilinear interpolation of the corner values c[x + 2y + 4z] at fractions t, with the
/// gradient in metres per metre (inv_h = 1 / voxel size).
float interpolate(const float c[8], const Eigen::Vector3f& t, float inv_h,
                  Eigen::Vector3f* gradient) {
  const float x00 = c[0] + t.x() * (c[1] - c[0]), x10 = c[2] + t.x() * (c[3] - c[2]);
  const float x01 = c[4] + t.x() * (c[5] - c[4]), x11 = c[6] + t.x() * (c[7] - c[6]);
  const float y0 = x00 + t.y() * (x10 - x00), y1 = x01 + t.y() * (x11 - x01);
  const float dx0 = (1 - t.y()) * (c[1] - c[0]) + t.y() * (c[3] - c[2]);
  const float dx1 = (1 - t.y()) * (c[5] - c[4]) + t.y() * (c[7] - c[6]);
  gradient->x() = ((1 - t.z()) * dx0 + t.z() * dx1) * inv_h;
  gradient->y() = ((1 - t.z()) * (x10 - x00) + t.z() * (x11 - x01)) * inv_h;
  gradient->z() = (y1 - y0) * inv_h;
  return y0 + t.z() * (y1 - y0);
}

}  // namespace

bool voxelDistance(const EsdfLayer& layer, const GlobalVoxelIndex& index, VoxelState* state,
                   float* distance) {
  const VoxelRef ref = locate(layer, nullptr, index);
  if (ref.voxel == nullptr) return false;
  distanceOf(layer, ref, state, distance);
  return true;
}

DistanceSample queryNearest(const EsdfLayer& layer, const Eigen::Vector3f& point) {
  if (!point.allFinite()) return DistanceSample{};
  return nearestSample(layer, nullptr, layer.globalVoxelIndexFromPoint(point));
}

DistanceSample queryInterpolated(const EsdfLayer& layer, const Eigen::Vector3f& point) {
  if (!point.allFinite()) return DistanceSample{};
  // Voxel centres sit at (i + 0.5) * h: the cell of centres around `point` starts at base.
  const Eigen::Vector3f scaled = point / layer.voxelSize() - Eigen::Vector3f::Constant(0.5f);
  const GlobalVoxelIndex base = gridIndexFromPoint(scaled, 1.0f);
  const Eigen::Vector3f t = scaled - base.cast<float>();
  // One hash lookup for the base corner's block; the other corners, the voxel that holds
  // `point` (one of them) and most sites are in it or next to it.
  const EsdfBlock* hint = locate(layer, nullptr, base).block;
  const GlobalVoxelIndex nearest = layer.globalVoxelIndexFromPoint(point);
  if (hint == nullptr) return nearestSample(layer, nullptr, nearest);
  float c[8];  // c[x + 2y + 4z]
  bool all_observed = true;
  for (int corner = 0; corner < 8; ++corner) {
    const GlobalVoxelIndex index =
        base + GlobalVoxelIndex(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
    const VoxelRef ref = locate(layer, hint, index);
    // Absent: no interpolation.
    if (ref.voxel == nullptr) return nearestSample(layer, hint, nearest);
    VoxelState state = VoxelState::kUnknown;
    distanceOf(layer, ref, &state, &c[corner]);
    all_observed = all_observed && state != VoxelState::kUnknown;
  }
  const float inv_h = 1.0f / layer.voxelSize();
  if (!all_observed) {
    // Unknown nearby: the nearest voxel answers; an unknown one's bound is interpolated.
    DistanceSample sample = nearestSample(layer, hint, nearest);
    if (sample.state == VoxelState::kUnknown && !std::isnan(sample.bound)) {
      sample.bound = interpolate(c, t, inv_h, &sample.gradient);
      sample.has_gradient = true;
    }
    return sample;
  }
  DistanceSample sample;
  sample.distance = interpolate(c, t, inv_h, &sample.gradient);
  sample.state = sample.distance <= 0.0f ? VoxelState::kOccupied : VoxelState::kFree;
  sample.has_gradient = true;
  return sample;
}

double lowerBesideSurface(double distance, double voxel, double margin_voxels, double* slope) {
  const double margin = margin_voxels * voxel;
  const double full_until = voxel + margin;  // lowered by the whole margin up to here
  double lowered = distance;
  double rate = 1.0;
  if (distance <= full_until) {
    lowered = distance - margin;
  } else if (distance < full_until + voxel) {
    lowered = distance - margin * (full_until + voxel - distance) / voxel;
    rate = 1.0 + margin_voxels;
  }
  if (slope != nullptr) *slope = rate;
  return std::max(0.0, lowered);
}

}  // namespace cblox
